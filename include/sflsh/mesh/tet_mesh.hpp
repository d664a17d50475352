#pragma once
#include "sflsh/core/types.hpp"

namespace sflsh {

/// A tetrahedral mesh: #N by 3 nodes (metres) and #T by 4 positively oriented
/// tetrahedra (see sflsh::Tets).
struct TetMesh {
  Points nodes;
  Tets elements;
  int num_nodes() const { return int(nodes.rows()); }
  int num_elements() const { return int(elements.rows()); }
};

/// A triangle surface mesh: #V by 3 vertices, #F by 3 faces (CCW from outside).
struct SurfaceMesh {
  Points vertices;
  Triangles faces;
};

}  // namespace sflsh
