// The benchmark's errors: a trace against the reference, and the floor of a basis
// (the reference projected onto it).
#include "bench/benchmark_internal.hpp"

namespace sflsh::bench_internal {

/// The floor trace of basis W (a.W by default): the skin displacement of the mass-weighted
/// projection of each reference frame onto span(W ⊗ I₃).
std::vector<Points> floor_trace(const Avatar& a, const Trace& ref, const Eigen::SparseMatrix<double, Eigen::RowMajor>* W) {
  const SubspaceProjector proj(W ? *W : a.W, simulated_lumped_mass(a));
  std::vector<Points> out;
  for (const Points& u : ref.nodal) out.push_back(surface_from_nodes(a, proj.project(u)));
  return out;
}

/// Region label of each skin vertex in `region` (tet_region of its tet), −1 elsewhere.
VecXi vertex_regions(const Avatar& a, const std::vector<int>& region) {
  VecXi out = VecXi::Constant(a.surface_rest.rows(), -1);
  for (int v : region) out[v] = a.tet_region[a.surface_tet[v]];
  return out;
}

void compare(const Trace& tr, const Trace& ref, const std::vector<int>& region, BenchRow& row) {
  const size_t F = std::min(tr.u.size(), ref.u.size());
  double diff2 = 0, ref2 = 0, sum = 0, mx = 0, peak = 0, peak_ref = 0;
  long count = 0;
  for (size_t f = 0; f < F; ++f)
    for (int v : region) {
      const Vec3 d = tr.u[f].row(v) - ref.u[f].row(v);
      const double e = d.norm();
      diff2 += d.squaredNorm();
      ref2 += ref.u[f].row(v).squaredNorm();
      sum += e;
      mx = std::max(mx, e);
      peak = std::max(peak, tr.u[f].row(v).norm());
      peak_ref = std::max(peak_ref, ref.u[f].row(v).norm());
      ++count;
    }
  row.err_mean_mm = count ? 1e3 * sum / double(count) : 0;
  row.err_max_mm = 1e3 * mx;
  row.rel_err = ref2 > 0 ? std::sqrt(diff2 / ref2) : 0;
  row.peak_ratio = peak_ref > 0 ? peak / peak_ref : 0;
  row.ms_median = percentile(tr.ms, 0.5);
  row.ms_p95 = percentile(tr.ms, 0.95);
}

}  // namespace sflsh::bench_internal
