#pragma once
// Shortest-path distance along the edges of a tet mesh (basis-internal): a
// geodesic through the flesh that never jumps across air between body parts
// (an arm and the torso beside it are far apart along the mesh).
#include <vector>

#include "sflsh/core/types.hpp"
#include "sflsh/mesh/tet_mesh.hpp"

namespace sflsh::basis {

/// The tet mesh's unique edges as an adjacency list with Euclidean lengths (m).
class EdgeGraph {
 public:
  explicit EdgeGraph(const TetMesh& mesh);
  int num_nodes() const { return int(start_.size()) - 1; }
  /// #N distance (m) from the nearest of `sources` along the edges (Dijkstra),
  /// +infinity beyond `cutoff` (the search stops there).
  VecX distances(const std::vector<int>& sources, double cutoff) const;

 private:
  std::vector<int> start_, neighbour_;  // CSR adjacency
  std::vector<double> length_;
};

}  // namespace sflsh::basis
