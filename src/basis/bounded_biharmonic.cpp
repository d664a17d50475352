#include "sflsh/basis/bounded_biharmonic.hpp"

#include <algorithm>
#include <atomic>
#include <exception>
#include <cmath>
#include <limits>
#include <mutex>
#include <numeric>
#include <sstream>

#include <thread>

#include "basis/bbw_internal.hpp"
#include "basis/edge_path_distance.hpp"
#include "sflsh/basis/depth_fraction.hpp"
#include "sflsh/asset/avatar.hpp"
#include "sflsh/fem/tet_operators.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/core/progress.hpp"
#include "sflsh/core/timer.hpp"

namespace sflsh::basis {
namespace {

using namespace bbw_internal;

/// Requires every connected component of the mesh to contain a fixed node.
void check_components_anchored(const TetMesh& mesh, const std::vector<char>& is_fixed) {
  const int n = mesh.num_nodes();
  std::vector<int> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int a) {
    while (parent[a] != a) a = parent[a] = parent[parent[a]];
    return a;
  };
  for (int e = 0; e < mesh.num_elements(); ++e)
    for (int a = 1; a < 4; ++a) parent[find(mesh.elements(e, a))] = find(mesh.elements(e, 0));
  std::vector<char> anchored(n, 0), used(n, 0);
  for (int e = 0; e < mesh.num_elements(); ++e)
    for (int a = 0; a < 4; ++a) used[mesh.elements(e, a)] = 1;
  for (int i = 0; i < n; ++i)
    if (is_fixed[i]) anchored[find(i)] = 1;
  for (int i = 0; i < n; ++i)
    require(!used[i] || anchored[find(i)], "bounded biharmonic weights: the mesh component containing node ", i,
            " has no handle or Dirichlet node, so its weights are undetermined");
  for (int i = 0; i < n; ++i)
    require(used[i] || is_fixed[i], "bounded biharmonic weights: node ", i,
            " belongs to no tet; remove unreferenced nodes or fix them");
}

MatX supported_qp(const TetMesh& mesh, const VecXi& fixed, const MatX& fixed_values, const VecX& support_radius,
                  const BbwOptions& options, BbwReport* report);

}  // namespace

std::string BbwReport::summary() const {
  std::ostringstream os;
  os << "bounded biharmonic weights: " << num_handles << " columns, " << num_nodes << " nodes (" << num_free
     << " free)\n"
     << "  active set: iterations max " << max_iterations << ", mean " << mean_iterations << ", largest inactive set "
     << max_inactive << " nodes, factorizations per column " << mean_factorizations << "\n"
     << "  KKT residual per iteration:";
  for (double r : kkt_history) os << ' ' << r;
  os << "\n  final KKT residual " << kkt_residual << "\n";
  if (nonzeros > 0)
    os << "  W: " << nonzeros << " nonzeros, bound violation " << max_bound_violation << ", partition-of-unity error "
       << partition_error << ", max Σ_k w_k before normalization " << max_sum_before_normalization << " ("
       << nodes_normalized << " rows rescaled" << (nodes_unreached ? ", " + std::to_string(nodes_unreached) + " Simulated rows no handle reaches" : std::string())
       << ")\n";
  os << "  time: operators " << seconds_setup << " s, active set " << seconds_active_set << " s";
  return os.str();
}

MatX bounded_biharmonic_qp(const TetMesh& mesh, const VecXi& fixed, const MatX& fixed_values,
                           const BbwOptions& options, BbwReport* report) {
  require(options.support_radius >= 0.0 && std::isfinite(options.support_radius),
          "bounded biharmonic weights: support radius must be a positive length in metres (or 0 for none), got ",
          options.support_radius);
  return supported_qp(mesh, fixed, fixed_values, VecX::Constant(fixed_values.cols(), options.support_radius), options,
                      report);
}

namespace {

/// Distance (m) of each free node to the fixed nodes with a nonzero value in `values`.
VecX distances_to_sources(const TetMesh& mesh, const VecXi& fixed, const VecX& values, const std::vector<int>& free_nodes) {
  const int nf = int(free_nodes.size());
  VecX dist = VecX::Constant(nf, std::numeric_limits<double>::infinity());
  for (int b = 0; b < fixed.size(); ++b) {
    if (values(b) == 0.0) continue;
    const Vec3 p = mesh.nodes.row(fixed(b)).transpose();
    for (int f = 0; f < nf; ++f) dist(f) = std::min(dist(f), (mesh.nodes.row(free_nodes[f]).transpose() - p).norm());
  }
  return dist;
}

/// Calls run(c) for every column c < C: one worker per core (or `threads`) pulls
/// columns from a shared counter (TBB is not linked into basis/; the columns are
/// independent and similar in cost). Rethrows the first error.
template <class Run>
void for_each_column_in_parallel(int C, int threads, Run& run) {
  std::atomic<int> next{0};
  std::exception_ptr error;
  std::mutex error_mutex;
  auto worker = [&] {
    for (int c; (c = next++) < C;) {
      try {
        run(c);
      } catch (...) {
        std::lock_guard<std::mutex> lock(error_mutex);
        if (!error) error = std::current_exception();
        next = C;
      }
    }
  };
  const int cores = std::max(1, int(std::thread::hardware_concurrency()));
  const int workers = std::max(1, std::min<int>(C, threads > 0 ? threads : cores));
  std::vector<std::thread> pool;
  for (int t = 0; t < workers; ++t) pool.emplace_back(worker);
  for (auto& t : pool) t.join();
  if (error) std::rethrow_exception(error);
}

/// The report of the column solves: iterations, KKT residuals, supports, times.
BbwReport solve_report(const std::vector<ColumnResult>& results, const SpMat& Qff, const MatX& qcols,
                       const std::vector<std::vector<char>>& outside, const std::vector<int>& support_nodes,
                       const VecX& support_radius, int n, double t_setup, double t_active) {
  const int C = int(results.size());
  const int nf = int(Qff.rows());
  BbwReport r;
  r.num_nodes = n;
  r.num_free = nf;
  r.num_handles = C;
  r.seconds_setup = t_setup;
  r.seconds_active_set = t_active;
  size_t hist = 0;
  double iters = 0.0;
  for (const auto& cr : results) {
    hist = std::max(hist, cr.history.size());
    r.max_iterations = std::max(r.max_iterations, cr.iterations);
    r.max_inactive = std::max(r.max_inactive, cr.max_inactive);
    iters += cr.iterations;
  }
  r.mean_iterations = C > 0 ? iters / C : 0.0;
  double facts = 0.0;
  for (const auto& cr : results) facts += cr.factorizations;
  r.mean_factorizations = C > 0 ? facts / C : 0.0;
  r.kkt_history.assign(hist, 0.0);
  for (const auto& cr : results)
    for (size_t i = 0; i < hist; ++i)
      r.kkt_history[i] = std::max(r.kkt_history[i], cr.history[std::min(i, cr.history.size() - 1)]);
  // Final residual of the returned (clamped) solutions.
  for (int c = 0; c < C && nf > 0; ++c) {
    const VecX& x = results[c].x;
    const double qn = std::max(qcols.col(c).lpNorm<Eigen::Infinity>(), std::numeric_limits<double>::min());
    r.kkt_residual =
        std::max(r.kkt_residual, kkt_residual(x, Qff * x + qcols.col(c), qn,
                                              outside.empty() || outside[c].empty() ? nullptr : &outside[c]));
  }
  r.support_radius = C > 0 ? support_radius.maxCoeff() : 0.0;
  for (int sn : support_nodes) r.max_support_nodes = std::max(r.max_support_nodes, sn);
  return r;
}

/// bounded_biharmonic_qp with a support radius per column (m; 0 = unrestricted).
MatX supported_qp(const TetMesh& mesh, const VecXi& fixed, const MatX& fixed_values, const VecX& support_radius,
                  const BbwOptions& options, BbwReport* report) {
  const int n = mesh.num_nodes();
  require(fixed_values.rows() == fixed.size(), "bounded biharmonic weights: ", fixed.size(), " fixed nodes but ",
          fixed_values.rows(), " rows of fixed values");
  require(fixed_values.allFinite(), "bounded biharmonic weights: fixed values must be finite");
  const int C = int(fixed_values.cols());
  std::vector<char> is_fixed(n, 0);
  for (int b = 0; b < fixed.size(); ++b) {
    require(fixed(b) >= 0 && fixed(b) < n, "bounded biharmonic weights: fixed node ", fixed(b), " out of range 0..",
            n - 1);
    require(!is_fixed[fixed(b)], "bounded biharmonic weights: node ", fixed(b), " is fixed twice");
    is_fixed[fixed(b)] = 1;
  }
  check_components_anchored(mesh, is_fixed);

  Timer timer;
  // Q = L M⁻¹ L with lumped M (Jacobson et al. 2011, eq. 5).
  const SpMat L = fem::stiffness_laplacian(mesh);
  const VecX m = fem::lumped_mass(mesh);
  const SpMat Q = L * m.cwiseInverse().asDiagonal() * L;

  std::vector<int> free_nodes;
  std::vector<int> free_index(n, -1);
  for (int i = 0; i < n; ++i)
    if (!is_fixed[i]) free_index[i] = int(free_nodes.size()), free_nodes.push_back(i);
  const int nf = int(free_nodes.size());
  // Selection matrices: Q_ff = P_f Q P_fᵀ, Q_fb = P_f Q P_bᵀ.
  SpMat Pf(nf, n), Pb(fixed.size(), n);
  {
    std::vector<Eigen::Triplet<double>> tf, tb;
    for (int c = 0; c < nf; ++c) tf.emplace_back(c, free_nodes[c], 1.0);
    for (int b = 0; b < fixed.size(); ++b) tb.emplace_back(b, fixed(b), 1.0);
    Pf.setFromTriplets(tf.begin(), tf.end());
    Pb.setFromTriplets(tb.begin(), tb.end());
  }
  SpMat Qff = Pf * Q * Pf.transpose();
  Qff.makeCompressed();
  const SpMat Qfb = Pf * Q * Pb.transpose();
  const MatX qcols = Qfb * fixed_values;  // #free by C linear terms

  // Local domains: distance of every free node to the fixed nodes that carry
  // a nonzero value in the column; start radius from the volume per column.
  const double volume = fem::lumped_mass(mesh).sum();
  const double radius0 = options.initial_radius_factor * std::cbrt(volume / std::max(C, 1));
  const bool compact = C > 0 && support_radius.maxCoeff() > 0.0;
  const EdgeGraph graph = compact ? EdgeGraph(mesh) : EdgeGraph(TetMesh{});
  std::vector<std::vector<char>> outside(compact ? C : 0);  // per column, #free
  std::vector<int> support_nodes(compact ? C : 0, 0);
  const double t_setup = timer.seconds();

  timer.reset();
  std::vector<ColumnResult> results(C);
  {
    Progress progress("bounded biharmonic weights", C);
    std::mutex progress_mutex;
    std::atomic<int> done{0};
    auto run = [&](int c) {
      const VecX dist = distances_to_sources(mesh, fixed, fixed_values.col(c), free_nodes);
      if (compact && support_radius[c] > 0.0) {
        std::vector<int> sources;
        for (int b = 0; b < fixed.size(); ++b)
          if (fixed_values(b, c) != 0.0) sources.push_back(fixed(b));
        const VecX path = graph.distances(sources, support_radius[c]);
        outside[c].assign(size_t(nf), 0);
        for (int f = 0; f < nf; ++f) {
          outside[c][f] = !(path(free_nodes[f]) <= support_radius[c]);
          support_nodes[c] += !outside[c][f];
        }
      }
      results[c] = solve_column(Qff, qcols.col(c), dist, radius0, options, c,
                                outside.empty() || outside[c].empty() ? nullptr : &outside[c]);
      const int d = ++done;
      if (options.show_progress) {
        std::lock_guard<std::mutex> lock(progress_mutex);
        progress.update(d);
      }
    };
    if (nf > 0) for_each_column_in_parallel(C, options.threads, run);
    if (options.show_progress) progress.finish();
  }
  const double t_active = timer.seconds();

  MatX W(n, C);
  for (int b = 0; b < fixed.size(); ++b) W.row(fixed(b)) = fixed_values.row(b);
  for (int c = 0; c < C && nf > 0; ++c)
    for (int f = 0; f < nf; ++f) W(free_nodes[f], c) = results[c].x(f);

  if (report)
    *report = solve_report(results, Qff, qcols, outside, support_nodes, support_radius, n, t_setup, t_active);
  return W;
}

}  // namespace

VecX bone_weight(const Eigen::SparseMatrix<double, Eigen::RowMajor>& W) {
  VecX s = W * VecX::Ones(W.cols());
  return (VecX::Ones(W.rows()) - s).cwiseMax(0.0).cwiseMin(1.0);
}

Eigen::SparseMatrix<double, Eigen::RowMajor> bounded_biharmonic_weights(const TetMesh& mesh, const VecXi& node_role,
                                                                        const VecXi& handle_nodes,
                                                                        const BbwOptions& options, BbwReport* report) {
  const int n = mesh.num_nodes();
  const int K = int(handle_nodes.size());
  require(node_role.size() == n, "bounded biharmonic weights: node_role has ", node_role.size(),
          " entries, expected #N = ", n);
  require(K > 0, "bounded biharmonic weights: no handles");
  std::vector<char> is_handle(n, 0);
  for (int k = 0; k < K; ++k) {
    const int i = handle_nodes(k);
    require(i >= 0 && i < n, "bounded biharmonic weights: handle ", k, " node ", i, " out of range 0..", n - 1);
    require(node_role(i) == int(NodeRole::Simulated), "bounded biharmonic weights: handle ", k, " node ", i,
            " has role ", node_role(i), ", expected Simulated (0)");
    require(!is_handle[i], "bounded biharmonic weights: handles share node ", i);
    is_handle[i] = 1;
  }
  const bool blend = options.bone_condition == BoneCondition::DepthBlend;
  require(!blend || options.normalization_floor > 0.0,
          "bounded biharmonic weights: normalization_floor must be positive, got ", options.normalization_floor);
  std::vector<int> fixed;
  std::vector<int> value_col;  // handle column with value 1, or −1 for a Dirichlet zero
  for (int k = 0; k < K; ++k) fixed.push_back(handle_nodes(k)), value_col.push_back(k);
  for (int i = 0; i < n; ++i) {
    const int role = node_role(i);
    require(role >= 0 && role <= 2, "bounded biharmonic weights: node_role(", i, ") = ", role,
            ", expected 0 (Simulated), 1 (Skinned) or 2 (Bone)");
    // DepthBlend: bone nodes are free in the QPs (their rows are zeroed below).
    if (role == int(NodeRole::Skinned) || (role == int(NodeRole::Bone) && !blend))
      fixed.push_back(i), value_col.push_back(-1);
  }
  VecXi fixed_v = Eigen::Map<VecXi>(fixed.data(), Eigen::Index(fixed.size()));
  MatX values = MatX::Zero(Eigen::Index(fixed.size()), K);
  for (size_t b = 0; b < fixed.size(); ++b)
    if (value_col[b] >= 0) values(Eigen::Index(b), value_col[b]) = 1.0;

  // Support radius of each handle (m; 0 = unrestricted).
  require(options.support_radius >= 0.0 && std::isfinite(options.support_radius),
          "bounded biharmonic weights: support radius must be a positive length in metres (or 0 for none), got ",
          options.support_radius);
  require(options.support_spacing_factor >= 0.0 && std::isfinite(options.support_spacing_factor),
          "bounded biharmonic weights: support spacing factor must be positive (or 0 for none), got ",
          options.support_spacing_factor);
  require(!(options.support_radius > 0.0 && options.support_spacing_factor > 0.0),
          "bounded biharmonic weights: give a support radius or a support spacing factor, not both");
  VecX radius = VecX::Constant(K, options.support_radius);
  if (options.support_spacing_factor > 0.0) {
    require(K >= 2, "bounded biharmonic weights: a support spacing factor needs at least 2 handles, got ", K);
    for (int k = 0; k < K; ++k) {
      double nearest = std::numeric_limits<double>::infinity();
      for (int l = 0; l < K; ++l)
        if (l != k) nearest = std::min(nearest, (mesh.nodes.row(handle_nodes(k)) - mesh.nodes.row(handle_nodes(l))).norm());
      radius[k] = options.support_spacing_factor * nearest;
    }
  }

  BbwReport local;
  BbwReport& r = report ? *report : local;
  MatX Wd = supported_qp(mesh, fixed_v, values, radius, options, &r);

  // Dirichlet: rescale rows with Σ_k w_k > 1. DepthBlend: every Simulated row
  // to b_i · w̃ / max(Σ w̃, floor), other rows 0 (see the header). Then sparsify.
  const VecX depth = blend ? depth_fraction(mesh, node_role) : VecX();
  std::vector<Eigen::Triplet<double>> trip;
  for (int i = 0; i < n; ++i) {
    const double s = Wd.row(i).sum();
    if (blend && node_role(i) != int(NodeRole::Simulated)) continue;
    r.max_sum_before_normalization = std::max(r.max_sum_before_normalization, s);
    if (blend) {
      if (s < options.normalization_floor) ++r.nodes_unreached;
      else ++r.nodes_normalized;
      Wd.row(i) *= depth[i] / std::max(s, options.normalization_floor);
    } else if (s > 1.0) {
      Wd.row(i) /= s;
      ++r.nodes_normalized;
    }
    for (int k = 0; k < K; ++k)
      if (std::abs(Wd(i, k)) >= options.drop_tolerance) trip.emplace_back(i, k, Wd(i, k));
  }
  Eigen::SparseMatrix<double, Eigen::RowMajor> W(n, K);
  W.setFromTriplets(trip.begin(), trip.end());
  W.makeCompressed();

  const VecX sums = W * VecX::Ones(K);
  const VecX wb = bone_weight(W);
  r.max_bound_violation = 0.0;
  for (int i = 0; i < W.outerSize(); ++i)
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(W, i); it; ++it)
      r.max_bound_violation = std::max({r.max_bound_violation, -it.value(), it.value() - 1.0});
  r.max_bound_violation = std::max({r.max_bound_violation, (sums.array() - 1.0).maxCoeff(), -sums.minCoeff()});
  r.partition_error = (sums + wb - VecX::Ones(n)).lpNorm<Eigen::Infinity>();
  r.nonzeros = W.nonZeros();
  return W;
}

}  // namespace sflsh::basis
