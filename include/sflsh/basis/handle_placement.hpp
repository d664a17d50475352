#pragma once
// Placement of the control handles of the reduced basis (seed §4: "control
// points distributed throughout the body ... denser sampling on areas with
// stronger soft-tissue deformation").
//
// Two steps:
//  1. Allocation: K handles are shared among body regions (labels per node):
//     every region with Simulated nodes gets at least `min_per_region`, the
//     rest go proportionally to the region's thickness-weighted soft volume
//     (allocate_handles: Sainte-Laguë apportionment).
//  2. Farthest-point sampling, region by region: the next handle goes to the
//     region furthest below its quota, at that region's Simulated node farthest
//     (geodesic, over the tet edge graph) from every handle chosen so far and
//     from the Dirichlet nodes (Bone, Skinned).
// Why regions: a single farthest-point sampling measured from the bones put all
// 64 handles of the default body on the torso: a limb's flesh is a
// thin shell, so every limb node is "close to bone" and the thick torso won
// every pick, leaving legs and arms with no soft weight at all.
#include <vector>

#include "sflsh/core/types.hpp"
#include "sflsh/mesh/tet_mesh.hpp"

namespace sflsh::basis {

/// K handles: node indices into the tet mesh and their positions.
struct HandleSet {
  VecXi nodes;      ///< #K distinct Simulated node indices
  Points positions; ///< #K by 3 (m), = mesh.nodes rows of `nodes`
};

struct HandlePlacementOptions {
  /// Spacing ∝ thickness^(−α) within a region: tet edges count as |e|·(t/t̄)^α
  /// in the sampling metric, so thick flesh gets more handles (handle density
  /// in a volume ∝ t^(3α): α = 0.5 gives 5× as many per m^3 where flesh is 3×
  /// thicker).
  double thickness_exponent = 0.5;
  /// Allocation weight of a region: Σ over its Simulated nodes of lumped
  /// volume · (t/t̄)^β (m^3). β = 0: handles ∝ soft volume; β > 0 favours
  /// thick, fat-rich regions (belly, buttocks, thighs). On the default body at
  /// K = 64, β = 0, 0.5 and 1 give the same skin coverage (28.1, 28.1, 27.6 %).
  double allocation_thickness_exponent = 0.5;
  /// Minimum handles per region that holds at least `min_region_fraction` of
  /// the total allocation weight (fewer only when K is smaller than regions ×
  /// minimum, or a region has fewer nodes). Smaller regions — e.g. the few
  /// Simulated nodes whose tets are labelled head or foot at the border of a
  /// skinned part — get handles only in proportion to their weight.
  /// 4 since the handle allocation change (2 before): at K = 96 it lowers rel_err
  /// on all four bench motions (mean 0.242 → 0.234) and the arms' and neck's
  /// by 10–25 % (scripts/results/handle_count_and_allocation.md).
  int min_per_region = 4;
  double min_region_fraction = 0.01;
  /// The distance to the nearest Dirichlet node counts this many times in the
  /// sampling metric (min over handles and Dirichlet nodes). > 1 keeps thin
  /// shells (limbs) from reducing every candidate to "one shell thickness from
  /// bone": handles then spread along the limb, and still stay off the bone
  /// surface and the skinned regions' borders.
  double dirichlet_distance_scale = 4.0;
  /// Only used when the mesh has no Dirichlet node: picks the first handle.
  unsigned seed = 0;
};

/// Sainte-Laguë apportionment of `K` handles among regions with non-negative
/// `weights` (#R) and `capacity` (#R, max handles a region can hold, e.g. its
/// Simulated node count): first, regions with capacity > 0 and weight ≥
/// min_fraction · Σ weights are raised to min(min_per_region, capacity), one handle at a time to the region with the
/// largest weights[r] / (n_r + 1/2); then each further handle goes to the
/// region with spare capacity and the largest weights[r] / (n_r + 1/2). Ties go
/// to the lowest index. Returns #R counts summing to min(K, Σ capacity).
VecXi allocate_handles(const VecX& weights, const VecXi& capacity, int K, int min_per_region,
                       double min_fraction = 0.0);

/// Region label of each node: the region (index into `tet_region`'s values,
/// 0..num_regions−1) holding the largest volume among the node's incident tets;
/// −1 for nodes in no tet. `tet_region`: #T labels.
VecXi node_regions_from_tets(const TetMesh& mesh, const VecXi& tet_region, int num_regions);

/// Picks `K` handles among the Simulated nodes (`node_role` #N, NodeRole).
/// `thickness`: #N tissue thickness (m) or empty for uniform; `node_region`:
/// #N region labels ≥ 0 (any value for non-Simulated nodes) or empty for one
/// region. Allocation and sampling as described at the top of this file.
/// Deterministic: ties go to the lowest region and node index; no randomness
/// unless there is no Dirichlet node. Fails if there are fewer than K
/// Simulated nodes, thickness is not positive or a label is negative.
HandleSet select_handles(const TetMesh& mesh, const VecXi& node_role, int K, const VecX& thickness = VecX(),
                         const VecXi& node_region = VecXi(), const HandlePlacementOptions& options = {});

/// User-given handle positions (#K by 3, m): each snaps to the nearest
/// Simulated node. Fails, naming the handle, if a position lies farther than
/// `tolerance` (m) outside the tet mesh, or if two handles snap to one node.
HandleSet snap_handles(const TetMesh& mesh, const VecXi& node_role, const Points& positions,
                       double tolerance = 0.01);

}  // namespace sflsh::basis
