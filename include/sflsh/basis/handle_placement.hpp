#pragma once
// Placement of the control handles of the reduced basis (seed §4: "control
// points distributed throughout the body ... denser sampling on areas with
// stronger soft-tissue deformation").
#include "sflsh/core/types.hpp"
#include "sflsh/mesh/tet_mesh.hpp"

namespace sflsh::basis {

/// K handles: node indices into the tet mesh and their positions.
struct HandleSet {
  VecXi nodes;      ///< #K distinct Simulated node indices
  Points positions; ///< #K by 3 (m), = mesh.nodes rows of `nodes`
};

struct HandlePlacementOptions {
  /// Spacing ∝ thickness^(−α): tet edges count as |e|·(t/t̄)^α in the
  /// sampling metric, so thick flesh gets more handles (handle density in a
  /// volume ∝ t^(3α): α = 0.5 gives 5× as many per m^3 where flesh is 3×
  /// thicker).
  double thickness_exponent = 0.5;
  /// Only used when the mesh has no Dirichlet node: picks the first handle.
  unsigned seed = 0;
};

/// Picks `K` handles among the Simulated nodes (`node_role` #N, NodeRole) by
/// farthest-point sampling in the geodesic metric of the tet edge graph, with
/// edge lengths scaled by the tissue thickness (`thickness` #N in m, or empty
/// for uniform). The distance field starts from the Dirichlet nodes (Bone,
/// Skinned), so each new handle is the Simulated node farthest from the bones,
/// the skinned regions and the handles chosen so far: a handle right next to
/// a Dirichlet node would carry a useless, steep weight. Deterministic: ties
/// go to the lowest node index; no randomness unless there is no Dirichlet node.
/// Fails if there are fewer than K Simulated nodes or thickness is not positive.
HandleSet select_handles(const TetMesh& mesh, const VecXi& node_role, int K, const VecX& thickness = VecX(),
                         const HandlePlacementOptions& options = {});

/// User-given handle positions (#K by 3, m): each snaps to the nearest
/// Simulated node. Fails, naming the handle, if a position lies farther than
/// `tolerance` (m) outside the tet mesh, or if two handles snap to one node.
HandleSet snap_handles(const TetMesh& mesh, const VecXi& node_role, const Points& positions,
                       double tolerance = 0.01);

}  // namespace sflsh::basis
