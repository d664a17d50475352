#include "sflsh/basis/basis_coverage.hpp"

#include <iomanip>
#include <limits>
#include <sstream>

#include "sflsh/asset/avatar.hpp"
#include "sflsh/core/error.hpp"

namespace sflsh::basis {

BasisCoverage basis_coverage(const Eigen::SparseMatrix<double, Eigen::RowMajor>& W, const VecXi& node_role,
                             const VecXi& surface_nodes, const VecXi& node_region, int num_regions,
                             const VecXi& handle_nodes, double threshold) {
  const Eigen::Index n = W.rows();
  require(node_role.size() == n && node_region.size() == n, "basis coverage: node_role (", node_role.size(),
          ") and node_region (", node_region.size(), ") must have #N = ", n, " entries");
  require(num_regions >= 0, "basis coverage: negative region count");
  BasisCoverage c;
  c.threshold = threshold;
  c.regions.resize(num_regions);
  auto region_of = [&](int i) -> RegionCoverage* {
    const int r = node_region[i];
    require(r < num_regions, "basis coverage: node ", i, " has region ", r, ", expected < ", num_regions);
    return r >= 0 ? &c.regions[r] : nullptr;
  };
  const VecX sum = W * VecX::Ones(W.cols());
  std::vector<char> seen(n, 0);
  for (Eigen::Index s = 0; s < surface_nodes.size(); ++s) {
    const int i = surface_nodes[s];
    require(i >= 0 && i < n, "basis coverage: surface node ", i, " out of range [0, ", n, ")");
    if (seen[i] || node_role[i] != int(NodeRole::Simulated)) continue;
    seen[i] = 1;
    const bool covered = sum[i] >= threshold;
    ++c.skin_nodes;
    c.covered += covered;
    if (RegionCoverage* rc = region_of(i)) {
      ++rc->skin_nodes;
      rc->covered += covered;
    }
  }
  for (Eigen::Index k = 0; k < handle_nodes.size(); ++k) {
    require(handle_nodes[k] >= 0 && handle_nodes[k] < n, "basis coverage: handle node ", handle_nodes[k],
            " out of range");
    if (RegionCoverage* rc = region_of(handle_nodes[k])) ++rc->handles;
  }
  return c;
}

std::string BasisCoverage::describe(const std::vector<std::string>& names) const {
  std::ostringstream o;
  o << std::fixed << std::setprecision(1) << "soft coverage: " << 100.0 * share() << " % of " << skin_nodes
    << " simulated skin nodes have sum_k W_k >= " << threshold << "\n";
  for (size_t r = 0; r < regions.size(); ++r) {
    const RegionCoverage& g = regions[r];
    if (g.handles == 0 && g.skin_nodes == 0) continue;
    const std::string name = r < names.size() ? names[r] : "region " + std::to_string(r);
    o << "  " << std::left << std::setw(10) << name << std::right << std::setw(4) << g.handles << (g.handles == 1 ? " handle,  " : " handles, ")
      << std::setw(5) << g.skin_nodes << " skin nodes, " << std::setw(5) << 100.0 * g.share() << " % covered\n";
  }
  return o.str();
}

VecXi nearest_nodes(const Points& nodes, const Points& positions) {
  VecXi out(positions.rows());
  for (Eigen::Index k = 0; k < positions.rows(); ++k) {
    double best = std::numeric_limits<double>::infinity();
    int arg = -1;
    for (Eigen::Index i = 0; i < nodes.rows(); ++i) {
      const double d = (nodes.row(i) - positions.row(k)).squaredNorm();
      if (d < best) best = d, arg = int(i);
    }
    require(arg >= 0, "nearest_nodes: no nodes");
    out[k] = arg;
  }
  return out;
}

}  // namespace sflsh::basis
