#pragma once
// How much of the simulated skin the reduced basis can move: the
// share of Simulated outer-surface nodes whose handle weights sum to at least
// a threshold, overall and per body region, with the handles per region. A
// node with Σ_k W_k = 0 is skinned rigidly although it is "simulated".
#include <string>
#include <vector>

#include <Eigen/Sparse>

#include "sflsh/core/types.hpp"

namespace sflsh::basis {

struct RegionCoverage {
  int handles = 0;     ///< handles whose node lies in the region
  int skin_nodes = 0;  ///< Simulated outer-surface nodes of the region
  int covered = 0;     ///< of those, nodes with Σ_k W_k ≥ threshold
  double share() const { return skin_nodes ? double(covered) / skin_nodes : 0.0; }
};

struct BasisCoverage {
  double threshold = 0.5;
  int skin_nodes = 0, covered = 0;   ///< over all regions
  std::vector<RegionCoverage> regions;  ///< by region index
  double share() const { return skin_nodes ? double(covered) / skin_nodes : 0.0; }
  /// "soft coverage: 96.1 % of 5,321 simulated skin nodes have Σ_k W_k ≥ 0.5"
  /// and one line "region: handles, skin nodes, coverage" per region with
  /// handles or skin nodes; `names` #R (a missing name prints the index).
  std::string describe(const std::vector<std::string>& names) const;
};

/// Coverage of the basis `W` (#N by #K): `node_role` #N (NodeRole),
/// `surface_nodes` the outer-surface node indices, `node_region` #N labels in
/// [0, num_regions) (or −1: counted only in the totals), `handle_nodes` #K.
BasisCoverage basis_coverage(const Eigen::SparseMatrix<double, Eigen::RowMajor>& W, const VecXi& node_role,
                             const VecXi& surface_nodes, const VecXi& node_region, int num_regions,
                             const VecXi& handle_nodes, double threshold = 0.5);

/// Index of the node nearest to each row of `positions` (#K by 3, m) among
/// `nodes` (#N by 3); ties go to the lowest index.
VecXi nearest_nodes(const Points& nodes, const Points& positions);

}  // namespace sflsh::basis
