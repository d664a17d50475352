#pragma once
// Quality optimization of a tet mesh by moving its inner nodes: after the
// shape stage has placed the nodes, tets whose smallest dihedral angle fell
// below a target are improved by relocating their interior nodes (freely) and
// their inner-boundary nodes (sliding in a given tangent plane), leaving the
// outer boundary untouched. Topology is unchanged.
#include <functional>
#include <vector>

#include "sflsh/core/types.hpp"
#include "sflsh/mesh/tet_mesh.hpp"

namespace sflsh {

/// How a node may move.
enum class NodeFreedom : char {
  Fixed = 0,  ///< stays (e.g. on the skin)
  Free = 1,   ///< any direction (interior nodes)
  Slide = 2,  ///< only in the plane orthogonal to its normal (nodes on an inner surface)
  Surface = 3,  ///< along the outer surface: every candidate goes through project_to_surface
};

struct InteriorSmoothingOptions {
  /// Nodes of tets whose smallest dihedral angle is below this (deg) are moved.
  double target_deg = 10.0;
  /// Sweeps over the nodes of the remaining bad tets (stops early when no node moves).
  int passes = 12;
  /// A node never ends farther than this fraction of its shortest incident
  /// edge (measured when the optimization starts) from where it started.
  double max_displacement_fraction = 0.5;
};

struct InteriorSmoothingReport {
  int below_target_before = 0, below_target_after = 0;  ///< tets below target_deg
  double min_dihedral_before = 0, min_dihedral_after = 0;  ///< deg, over the whole mesh
  int inverted_before = 0, inverted_after = 0;  ///< tets with signed volume <= 0
  /// Tets still below target_deg whose four nodes are all Fixed (no move can help them).
  int below_target_all_fixed = 0;
  int moves = 0;                                ///< accepted node moves
  int nodes_moved = 0;                          ///< distinct nodes that moved
  double max_displacement = 0;                  ///< m, largest distance a node moved
  int passes = 0;                               ///< sweeps run
};

/// Moves the Free and Slide nodes (`freedom`, #N) of the tets below
/// options.target_deg to raise the smallest dihedral angle of each node's star
/// (the tets around it). Per node and sweep the candidates are the smart
/// Laplacian point (the mean of its edge neighbours, and halfway to it) and
/// steps of 30 %, 10 % and 3 % of its shortest incident edge along the 26
/// lattice directions and the normals of the faces opposite it in its worst
/// tet; a Slide node's step loses its component along `slide_normals` row n
/// (#N by 3, unit, read only for Slide nodes). The best candidate is kept
/// only if it raises the star's smallest angle, so no tet of the star ends
/// worse than the star's worst before, no tet inverts, and the mesh's
/// smallest angle never decreases. A Surface node's candidates are mapped by
/// `project_to_surface` (e.g. the closest point of the skin; required when
/// any node is Surface), so it stays on that surface. Deterministic.
InteriorSmoothingReport smooth_interior_nodes(TetMesh& mesh, const std::vector<NodeFreedom>& freedom,
                                              const Points& slide_normals,
                                              const InteriorSmoothingOptions& options = {},
                                              const std::function<Vec3(const Vec3&)>& project_to_surface = {});

}  // namespace sflsh
