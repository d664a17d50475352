#pragma once
// Sliver repair by node relocation: a deterministic hill climb that moves
// free nodes of flat tets to raise the smallest dihedral angle of their star.
#include <vector>

#include "sflsh/core/types.hpp"
#include "sflsh/mesh/tet_mesh.hpp"

namespace sflsh {

struct SliverRepairOptions {
  double target_deg = 10.0;  ///< tets below this smallest dihedral angle are worked on
  int passes = 8;            ///< sweeps over the remaining slivers
};

struct SliverRepairReport {
  int slivers_before = 0, slivers_after = 0;  ///< tets below target_deg
  int moves = 0;                              ///< accepted node moves
  double min_dihedral_before = 0, min_dihedral_after = 0;  ///< deg
};

/// Moves nodes with `movable[n] != 0` (#N flags) of tets whose smallest
/// dihedral angle is below target_deg. Each move tries fixed directions (the
/// 26 lattice directions and both normals of the face opposite the node) at
/// steps of 30 %, 10 % and 3 % of the shortest incident edge and keeps the
/// one that most raises the smallest dihedral angle over the node's star, so
/// no tet of the star gets worse than that star's worst and none inverts.
/// Topology is unchanged; the result is deterministic.
SliverRepairReport repair_slivers(TetMesh& mesh, const std::vector<char>& movable,
                                  const SliverRepairOptions& options = {});

}  // namespace sflsh
