#pragma once
// Internals shared by fit_materials and fit_shape_map: one simulation per
// subject shared by its residual blocks, the per-vertex residual, the
// per-iteration log, and the solver settings.
#include <ceres/ceres.h>

#include <functional>
#include <string>
#include <vector>

#include "sflsh/core/error.hpp"
#include "sflsh/core/timer.hpp"
#include "sflsh/fit/material_fit.hpp"

namespace sflsh::fit_detail {

/// One simulation of the current parameters, shared by every residual block
/// (Ceres evaluates the blocks one after another at the same point).
class SharedRun {
 public:
  SharedRun(const Avatar& avatar, const FitParameters& params, const BoneSequence& bones, std::vector<int> steps,
            std::vector<int> vertices, const MaterialFitOptions& options)
      : avatar_(avatar), params_(params), bones_(bones), steps_(std::move(steps)), vertices_(std::move(vertices)),
        options_(options) {}

  /// The run at parameters x (#p), with Jacobians when `jacobian`.
  const SurfaceRun& get(const double* x, bool jacobian) {
    const Eigen::Map<const VecX> p(x, params_.size());
    if (valid_ && p == p_ && (has_jacobian_ || !jacobian)) return run_;
    valid_ = false;
    Timer timer;
    if (!jacobian || !options_.numeric) {
      run_ = simulate_surface(avatar_, params_, p, options_.damping, bones_, steps_, vertices_, jacobian);
      ++simulations;
      if (jacobian) ++jacobian_simulations, ms_jacobian += timer.ms();
      else ++plain_simulations, ms_plain += timer.ms();
    } else {
      // Central differences of whole runs: 2 runs per parameter.
      run_ = simulate_surface(avatar_, params_, p, options_.damping, bones_, steps_, vertices_, false);
      ms_plain += timer.ms();
      ++simulations, ++plain_simulations;
      timer.reset();
      const int P = params_.size();
      run_.jacobian.assign(steps_.size(), MatX::Zero(3 * run_.surface[0].rows(), P));
      for (int i = 0; i < P; ++i) {
        VecX pp = p, pm = p;
        pp[i] += options_.numeric_step;
        pm[i] -= options_.numeric_step;
        const SurfaceRun a = simulate_surface(avatar_, params_, pp, options_.damping, bones_, steps_, vertices_, false);
        const SurfaceRun b = simulate_surface(avatar_, params_, pm, options_.damping, bones_, steps_, vertices_, false);
        simulations += 2;
        for (size_t f = 0; f < steps_.size(); ++f) {
          const MatXr d = (a.surface[f] - b.surface[f]) / (2 * options_.numeric_step);
          run_.jacobian[f].col(i) = Eigen::Map<const VecX>(d.data(), d.size());
        }
      }
      ++jacobian_simulations;
      ms_jacobian += timer.ms();
    }
    p_ = p;
    has_jacobian_ = jacobian;
    valid_ = true;
    return run_;
  }

  int simulations = 0, plain_simulations = 0, jacobian_simulations = 0;
  double ms_plain = 0, ms_jacobian = 0;

 private:
  const Avatar& avatar_;
  const FitParameters& params_;
  const BoneSequence& bones_;
  std::vector<int> steps_, vertices_;
  const MaterialFitOptions& options_;
  VecX p_;
  bool valid_ = false, has_jacobian_ = false;
  SurfaceRun run_;
};

/// Residual x_v(t_f; p) − observed (3, m) of one vertex in one frame, with
/// p = P0 + Σ_k β_k P_k over parameter blocks [P0, P_1, ..., P_n] (n = #β;
/// one block P0 = p when there are no β).
class VertexCost : public ceres::CostFunction {
 public:
  VertexCost(SharedRun* run, int frame, int vertex, const Vec3& observed, int num_params, const VecX& betas)
      : run_(run), frame_(frame), vertex_(vertex), observed_(observed), betas_(betas), p_(num_params) {
    set_num_residuals(3);
    for (int k = 0; k <= betas.size(); ++k) mutable_parameter_block_sizes()->push_back(num_params);
  }
  bool Evaluate(double const* const* x, double* residuals, double** jacobians) const override {
    const int P = int(p_.size());
    p_ = Eigen::Map<const VecX>(x[0], P);
    for (int k = 0; k < betas_.size(); ++k) p_ += betas_[k] * Eigen::Map<const VecX>(x[k + 1], P);
    bool want = false;
    for (int k = 0; jacobians && k <= betas_.size(); ++k) want = want || jacobians[k] != nullptr;
    try {
      const SurfaceRun& r = run_->get(p_.data(), want);
      for (int c = 0; c < 3; ++c) residuals[c] = r.surface[frame_](vertex_, c) - observed_[c];
      if (want) {
        const MatX& J = r.jacobian[frame_];
        for (int k = 0; k <= betas_.size(); ++k) {
          if (!jacobians[k]) continue;
          const double scale = k == 0 ? 1.0 : betas_[k - 1];
          for (int c = 0; c < 3; ++c)
            for (int j = 0; j < P; ++j) jacobians[k][c * P + j] = scale * J(3 * vertex_ + c, j);
        }
      }
      return true;
    } catch (const Error&) {
      return false;  // e.g. an element inverted: Ceres shrinks its trust region
    }
  }

 private:
  SharedRun* run_;
  int frame_, vertex_;
  Vec3 observed_;
  VecX betas_;
  mutable VecX p_;
};

/// One line per Ceres iteration, in the style of its own progress output.
class ProgressLog : public ceres::IterationCallback {
 public:
  explicit ProgressLog(std::function<void(const std::string&)> log) : log_(std::move(log)) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& s) override {
    if (!log_) return ceres::SOLVER_CONTINUE;
    char buf[256];
    if (s.iteration == 0) log_("iter      cost        cost_change  |gradient|   |step|    tr_radius  iter_time  total_time");
    std::snprintf(buf, sizeof buf, "%4d  %12.6e  %11.3e  %10.3e  %9.3e  %9.3e  %8.2f s  %9.2f s%s", s.iteration, s.cost,
                  s.cost_change, s.gradient_max_norm, s.step_norm, s.trust_region_radius, s.iteration_time_in_seconds,
                  s.cumulative_time_in_seconds, s.iteration > 0 && !s.step_is_successful ? "  (rejected)" : "");
    log_(buf);
    return ceres::SOLVER_CONTINUE;
  }

 private:
  std::function<void(const std::string&)> log_;
};

/// Adds one residual block per (selected frame, selected vertex) of a subject.
inline void add_vertex_blocks(ceres::Problem& problem, SharedRun& run, const std::vector<int>& frames,
                              const std::vector<int>& vertices, const std::vector<Points>& observed, int num_params,
                              const VecX& betas, ceres::LossFunction* loss, const std::vector<double*>& blocks) {
  for (size_t f = 0; f < frames.size(); ++f)
    for (size_t i = 0; i < vertices.size(); ++i)
      problem.AddResidualBlock(new VertexCost(&run, int(f), int(i), observed[frames[f]].row(vertices[i]).transpose(),
                                              num_params, betas),
                               loss, blocks);
}

/// The robust loss of the options (null for "none"); throws on an unknown name.
inline std::unique_ptr<ceres::LossFunction> make_loss(const MaterialFitOptions& o) {
  require(o.loss == "none" || o.loss == "huber" || o.loss == "cauchy", "--loss must be none, huber or cauchy, got '",
          o.loss, "'");
  require(o.loss_scale > 0 && std::isfinite(o.loss_scale), "--loss-scale must be > 0 m, got ", o.loss_scale);
  if (o.loss == "huber") return std::make_unique<ceres::HuberLoss>(o.loss_scale);
  if (o.loss == "cauchy") return std::make_unique<ceres::CauchyLoss>(o.loss_scale);
  return nullptr;
}

/// Levenberg–Marquardt, dense normal equations (few parameters), one thread
/// (blocks of a subject share one simulation), progress through `progress`.
inline ceres::Solver::Options solver_options(const MaterialFitOptions& o, ceres::IterationCallback* progress) {
  ceres::Solver::Options so;
  so.minimizer_type = ceres::TRUST_REGION;
  so.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  so.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;
  so.max_num_iterations = o.max_iterations;
  so.function_tolerance = o.function_tolerance;
  so.gradient_tolerance = 1e-12;
  so.parameter_tolerance = 1e-6;
  so.num_threads = 1;
  so.logging_type = ceres::SILENT;
  so.callbacks.push_back(progress);
  return so;
}

/// Every `stride`-th index in [0, n).
inline std::vector<int> strided(int n, int stride) {
  std::vector<int> out;
  for (int i = 0; i < n; i += stride) out.push_back(i);
  return out;
}

}  // namespace sflsh::fit_detail
