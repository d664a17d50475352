#pragma once
// Embedding of points in a tet mesh: containing (or nearest) tet and
// barycentric coordinates, e.g. the skin vertices in the simulation mesh.
#include "sflsh/core/types.hpp"
#include "sflsh/mesh/tet_mesh.hpp"

namespace sflsh {

struct PointEmbedding {
  VecXi tet;        ///< #P containing tet, or the nearest one for points outside
  MatXr bary;       ///< #P by 4 barycentric coordinates (>= 0, sum 1)
  VecX distance;    ///< #P |point - Σ bary x| (0 for points inside, m)
  int num_outside = 0;
};

/// Embeds `points` (#P by 3) in `mesh`. Points inside a tet get its exact
/// barycentric coordinates; points outside get the tet whose clamped
/// coordinates reproduce them best (searched in a uniform grid around them).
PointEmbedding embed_points(const TetMesh& mesh, const Points& points);

}  // namespace sflsh
