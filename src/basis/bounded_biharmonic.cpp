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

#include "basis/cholmod_llt.hpp"
#include "basis/edge_path_distance.hpp"
#include "sflsh/basis/depth_fraction.hpp"
#include "sflsh/asset/avatar.hpp"
#include "sflsh/fem/tet_operators.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/core/progress.hpp"
#include "sflsh/core/timer.hpp"

namespace sflsh::basis {
namespace {

using SpMat = Eigen::SparseMatrix<double>;

/// Node states of the active-set method: free (inactive), at a bound, or
/// outside the column's support (held at 0, not a bound: never released and
/// not part of the KKT test).
enum : char { kFree = 0, kLower = 1, kUpper = 2, kOutside = 3 };

/// Rows/cols `keep` (ascending) of the symmetric column-major A; `map[i]` is
/// the new index of old index i or −1.
SpMat principal_submatrix(const SpMat& A, const std::vector<int>& keep, const std::vector<int>& map) {
  std::vector<Eigen::Triplet<double>> trip;
  for (size_t c = 0; c < keep.size(); ++c)
    for (SpMat::InnerIterator it(A, keep[c]); it; ++it) {
      const int r = map[it.row()];
      if (r >= int(c)) trip.emplace_back(r, int(c), it.value());  // lower triangle is all CHOLMOD reads
    }
  SpMat S(int(keep.size()), int(keep.size()));
  S.setFromTriplets(trip.begin(), trip.end());
  S.makeCompressed();
  return S;
}

/// Dimensionless KKT residual of x for min ½xᵀAx + qᵀx, 0 ≤ x ≤ 1 with
/// gradient g = Ax + q (see BbwReport::kkt_residual).
/// Nodes marked in `outside` (when non-null) are held values, not bounds: skipped.
double kkt_residual(const VecX& x, const VecX& g, double qnorm, const std::vector<char>* outside = nullptr) {
  double r = 0.0;
  for (Eigen::Index i = 0; i < x.size(); ++i) {
    if (outside && (*outside)[size_t(i)]) continue;
    const double viol = std::max({0.0, -x(i), x(i) - 1.0});
    double pg;
    if (x(i) <= 0.0) pg = std::max(0.0, -g(i));
    else if (x(i) >= 1.0) pg = std::max(0.0, g(i));
    else pg = std::abs(g(i));
    r = std::max({r, viol, pg / qnorm});
  }
  return r;
}

struct ColumnResult {
  VecX x;
  std::vector<double> history;
  int iterations = 0;
  int max_inactive = 0;
  int factorizations = 0;
};

/// Solves the inactive-set systems Q_II x_I = −q_I − Q_IA x_A of one column's
/// active-set iterations. A fresh factorization per iteration dominated the
/// cost, while most iterations move only a few nodes at the support boundary;
/// so this keeps the CHOLMOD factor F of Q over a base set I0 and treats the
/// difference to the current set I as a bordered system (Schur complement,
/// i.e. a capacitance-matrix / Sherman–Morrison–Woodbury update; Hager 1989,
/// "Updating the inverse of a matrix"): nodes of I \ I0 are extra rows and
/// columns of Q, nodes of I0 \ I are held at their bound by Lagrange
/// multipliers. The columns F⁻¹B of the border are cached per node, so a
/// node that toggles back and forth costs one solve. When the cache would
/// exceed `max_border` columns, I becomes the new base and is refactored.
class InactiveSetSolver {
 public:
  InactiveSetSolver(const SpMat& A, int max_border) : A_(A), max_border_(max_border) {
    base_index_.assign(size_t(A.rows()), -1);
    cache_col_.assign(size_t(A.rows()), -1);
  }
  int factorizations() const { return factorizations_; }

  /// Overwrites x on the free nodes of `state` (others hold their bound value).
  void solve(const std::vector<char>& state, const VecX& q, VecX& x) {
    const int n = int(A_.rows());
    std::vector<int> added, held;  // I \ I0, I0 \ I
    int num_free = 0;
    for (int i = 0; i < n; ++i) {
      const bool is_free = state[i] == kFree;
      num_free += is_free;
      if (is_free && base_index_[i] < 0) added.push_back(i);
      if (!is_free && base_index_[i] >= 0) held.push_back(i);
    }
    int uncached = 0;
    for (int j : added) uncached += cache_col_[j] < 0;
    for (int j : held) uncached += cache_col_[j] < 0;
    if (!factored_ || cache_cols_ + uncached > max_border_) {
      refactor(state, num_free);
      added.clear(), held.clear();
    }
    const bool bordered = !added.empty() || !held.empty();
    // Right-hand side with every node of I0 ∪ added unknown: r = −q − Q x_out.
    VecX xo = x;
    for (int i : base_) xo(i) = 0.0;
    for (int i : added) xo(i) = 0.0;
    const VecX r = -(q + A_ * xo);
    MatX r0(base_.size(), 1);
    for (size_t c = 0; c < base_.size(); ++c) r0(Eigen::Index(c), 0) = r(base_[c]);
    const MatX y0 = llt_.solve(r0);
    if (!bordered) {
      for (size_t c = 0; c < base_.size(); ++c) x(base_[c]) = y0(Eigen::Index(c), 0);
      return;
    }
    // Cache F⁻¹B for new border nodes: B e_j = Q(I0, j) for an added node,
    // the unit vector of j for a held node.
    std::vector<int> fresh;
    for (int j : added)
      if (cache_col_[j] < 0) fresh.push_back(j);
    for (int j : held)
      if (cache_col_[j] < 0) fresh.push_back(j);
    if (!fresh.empty()) {
      MatX B = MatX::Zero(Eigen::Index(base_.size()), Eigen::Index(fresh.size()));
      for (size_t k = 0; k < fresh.size(); ++k) {
        const int j = fresh[k];
        if (base_index_[j] >= 0) {
          B(base_index_[j], Eigen::Index(k)) = 1.0;
        } else {
          for (SpMat::InnerIterator it(A_, j); it; ++it)
            if (base_index_[it.row()] >= 0) B(base_index_[it.row()], Eigen::Index(k)) = it.value();
        }
      }
      const MatX Zn = llt_.solve(B);
      if (Z_.cols() < cache_cols_ + Zn.cols())
        Z_.conservativeResize(Z_.rows(), std::max<Eigen::Index>(cache_cols_ + Zn.cols(), 2 * Z_.cols()));
      Z_.middleCols(cache_cols_, Zn.cols()) = Zn;
      for (size_t k = 0; k < fresh.size(); ++k) cache_col_[fresh[k]] = cache_cols_ + int(k);
      cache_cols_ += int(Zn.cols());
    }
    // Border order: added nodes, then held nodes. S = C − Bᵀ F⁻¹ B.
    std::vector<int> border = added;
    border.insert(border.end(), held.begin(), held.end());
    const int m = int(border.size());
    const int na = int(added.size());
    std::vector<int> zc(m);
    for (int k = 0; k < m; ++k) zc[k] = cache_col_[border[k]];
    MatX S(m, m);
    VecX rhs(m);
    for (int a = 0; a < m; ++a) {
      const int j = border[a];
      // Row a of Bᵀ applied to [F⁻¹B | y0].
      if (a >= na) {
        const int bi = base_index_[j];
        for (int b = 0; b < m; ++b) S(a, b) = -Z_(bi, zc[b]);
        rhs(a) = (state[j] == kUpper ? 1.0 : 0.0) - y0(bi, 0);
      } else {
        S.row(a).setZero();
        rhs(a) = r(j);
        for (SpMat::InnerIterator it(A_, j); it; ++it) {
          const int bi = base_index_[it.row()];
          if (bi < 0) continue;
          for (int b = 0; b < m; ++b) S(a, b) -= it.value() * Z_(bi, zc[b]);
          rhs(a) -= it.value() * y0(bi, 0);
        }
      }
    }
    for (int a = 0; a < na; ++a)  // C: Q between added nodes
      for (int b = 0; b < na; ++b) S(a, b) += A_.coeff(added[a], added[b]);
    const VecX s = S.partialPivLu().solve(rhs);
    VecX y = y0.col(0);
    for (int b = 0; b < m; ++b) y -= s(b) * Z_.col(zc[b]);
    for (size_t c = 0; c < base_.size(); ++c) x(base_[c]) = y(Eigen::Index(c));
    for (int a = 0; a < na; ++a) x(added[a]) = s(a);
    for (int j : held) x(j) = state[j] == kUpper ? 1.0 : 0.0;
  }

 private:
  void refactor(const std::vector<char>& state, int num_free) {
    for (int i : base_) base_index_[i] = -1;
    base_.clear();
    base_.reserve(size_t(num_free));
    for (int i = 0; i < int(A_.rows()); ++i)
      if (state[i] == kFree) base_index_[i] = int(base_.size()), base_.push_back(i);
    std::fill(cache_col_.begin(), cache_col_.end(), -1);
    cache_cols_ = 0;
    Z_.resize(Eigen::Index(base_.size()), std::min(max_border_, 64));
    llt_.factor(principal_submatrix(A_, base_, base_index_), "bounded biharmonic weights: inactive-set system");
    factored_ = true;
    ++factorizations_;
  }

  const SpMat& A_;
  const int max_border_;
  detail::CholmodLLT llt_;
  bool factored_ = false;
  int factorizations_ = 0;
  std::vector<int> base_, base_index_;  // I0 and its inverse (−1 outside)
  std::vector<int> cache_col_;          // column of Z_ caching F⁻¹B e_j, or −1
  int cache_cols_ = 0;
  MatX Z_;
};

/// One bound-constrained QP  min ½xᵀAx + qᵀx, 0 ≤ x ≤ 1, by the primal–dual
/// active-set method. `dist` (#free): distance (m) of each node to the fixed
/// nodes with nonzero value; nodes farther than `radius` start at the lower
/// bound (see BbwOptions::initial_radius_factor). Nodes marked in `outside`
/// (#free, when non-null) lie outside the column's support: held at 0.
ColumnResult solve_column(const SpMat& A, const VecX& q, const VecX& dist, double radius, const BbwOptions& opt,
                          int column, const std::vector<char>* outside = nullptr) {
  const int n = int(A.rows());
  const double qnorm = std::max(q.lpNorm<Eigen::Infinity>(), std::numeric_limits<double>::min());
  const double mtol = opt.multiplier_tolerance * qnorm;
  ColumnResult res;
  res.x = VecX::Zero(n);
  std::vector<char> state(n);
  for (int i = 0; i < n; ++i) state[i] = outside && (*outside)[i] ? kOutside : dist(i) <= radius ? kFree : kLower;
  std::vector<int> released(n, 0);  // releases in the conservative phase, see below
  std::vector<char> frozen(n, 0);

  InactiveSetSolver solver(A, opt.max_border_columns);
  VecX& x = res.x;
  for (int it = 1; it <= opt.max_iterations; ++it) {
    int num_free = 0;
    for (int i = 0; i < n; ++i) {
      if (state[i] != kFree) x(i) = state[i] == kUpper ? 1.0 : 0.0;
      num_free += state[i] == kFree;
    }
    if (num_free > 0) solver.solve(state, q, x);
    res.max_inactive = std::max(res.max_inactive, num_free);
    const VecX g = A * x + q;  // multipliers on the active set
    res.history.push_back(kkt_residual(x, g, qnorm, outside));
    res.iterations = it;
    res.factorizations = solver.factorizations();

    // Active-set update. Plain PDAS first; after opt.pdas_iterations add-only,
    // or release-only when nothing is violated. A node bound again after
    // opt.max_releases such releases stays bound ("frozen"): every node is
    // then released finitely often, so the iteration ends (add/release alone
    // can cycle on long, thin supports, seen with free bones), and the KKT
    // residual reports what freezing cost.
    const bool conservative = it > opt.pdas_iterations;
    bool primal_violation = false;
    for (int i = 0; i < n; ++i)
      if (state[i] == kFree && (x(i) < 0.0 || x(i) > 1.0)) primal_violation = true;
    bool changed = false;
    for (int i = 0; i < n; ++i) {
      if (state[i] == kFree) {
        if (x(i) < 0.0) state[i] = kLower, changed = true;
        else if (x(i) > 1.0) state[i] = kUpper, changed = true;
        if (state[i] != kFree && released[i] >= opt.max_releases) frozen[i] = 1;
      } else if (state[i] != kOutside && !(conservative && (primal_violation || frozen[i]))) {
        if ((state[i] == kLower && g(i) < -mtol) || (state[i] == kUpper && g(i) > mtol)) {
          state[i] = kFree;
          if (conservative) ++released[i];
          changed = true;
        }
      }
    }
    // Settled, or converged to within kkt_tolerance while nodes at the C¹
    // support boundary still toggle at round-off level (seen with free bones).
    if (!changed || res.history.back() <= opt.kkt_tolerance) {
      x = x.cwiseMax(0.0).cwiseMin(1.0);  // round-off on the inactive set
      return res;
    }
  }
  fail("bounded biharmonic weights: active-set iteration for column ", column, " did not settle in ",
       opt.max_iterations, " iterations (KKT residual ", res.history.back(), ")");
}

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
      VecX dist = VecX::Constant(nf, std::numeric_limits<double>::infinity());
      for (int b = 0; b < fixed.size(); ++b) {
        if (fixed_values(b, c) == 0.0) continue;
        const Vec3 p = mesh.nodes.row(fixed(b)).transpose();
        for (int f = 0; f < nf; ++f) dist(f) = std::min(dist(f), (mesh.nodes.row(free_nodes[f]).transpose() - p).norm());
      }
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
    // One worker per core pulls columns from a shared counter (TBB is not
    // linked into basis/; the columns are independent and similar in cost).
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
    const int workers = std::max(1, std::min<int>(C, options.threads > 0 ? options.threads : cores));
    std::vector<std::thread> pool;
    if (nf > 0)
      for (int t = 0; t < workers; ++t) pool.emplace_back(worker);
    for (auto& t : pool) t.join();
    if (error) std::rethrow_exception(error);
    if (options.show_progress) progress.finish();
  }
  const double t_active = timer.seconds();

  MatX W(n, C);
  for (int b = 0; b < fixed.size(); ++b) W.row(fixed(b)) = fixed_values.row(b);
  for (int c = 0; c < C && nf > 0; ++c)
    for (int f = 0; f < nf; ++f) W(free_nodes[f], c) = results[c].x(f);

  if (report) {
    BbwReport& r = *report;
    r = BbwReport{};
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
  }
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
