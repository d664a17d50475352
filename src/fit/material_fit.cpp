#include "sflsh/fit/material_fit.hpp"

#include <ceres/ceres.h>
#include <ceres/covariance.h>

#include <cmath>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>
#include <sstream>

#include <Eigen/Eigenvalues>

#include "sflsh/core/error.hpp"
#include "sflsh/core/timer.hpp"
#include "fit/fit_problem.hpp"
#include "sflsh/io/atomic_output.hpp"

namespace sflsh {
namespace {

using namespace fit_detail;

/// Per observed frame RMS over the vertices of simulated − observed (m).
std::vector<double> frame_rms(const SurfaceRun& run, const std::vector<Points>& observed) {
  std::vector<double> out;
  for (size_t f = 0; f < observed.size(); ++f)
    out.push_back(std::sqrt((run.surface[f] - observed[f]).rowwise().squaredNorm().mean()));
  return out;
}

double total_rms(const std::vector<double>& per_frame) {
  double s = 0;
  for (double v : per_frame) s += v * v;
  return per_frame.empty() ? 0 : std::sqrt(s / per_frame.size());
}

/// A 1-sigma factor exp(σ) as text ("x1.23", or "> x1000" past that).
std::string sigma_factor(double sigma) {
  if (!(sigma < std::log(1000.0))) return "> x1000";
  char buf[32];
  std::snprintf(buf, sizeof buf, "x%.3g", std::exp(sigma));
  return buf;
}

bool is_log(const FitParameter& p) {
  return p.kind == FitParameter::Kind::Young || p.kind == FitParameter::Kind::FungC;
}

}  // namespace

MaterialFitResult fit_materials(const Avatar& avatar, const FitParameters& params, const BoneSequence& bones,
                                const std::vector<int>& steps, const std::vector<Points>& observed,
                                const MaterialFitOptions& o) {
  require(steps.size() == observed.size() && !steps.empty(), "fit: ", steps.size(), " steps for ", observed.size(),
          " observed frames");
  require(o.vertex_stride >= 1 && o.frame_stride >= 1, "fit: vertex and frame strides must be >= 1");
  require(o.max_iterations >= 0, "--max-iterations must be >= 0");
  const int V = int(avatar.surface_rest.rows()), P = params.size();
  for (const Points& X : observed)
    require(X.rows() == V, "fit: an observed frame has ", X.rows(), " vertices, the avatar ", V);

  const std::vector<int> frames = strided(int(steps.size()), o.frame_stride), vertices = strided(V, o.vertex_stride);
  std::vector<int> fit_steps;
  for (int f : frames) fit_steps.push_back(steps[f]);

  MaterialFitResult res;
  for (const FitParameter& e : params.entries()) res.labels.push_back(e.label(avatar.materials));
  res.initial = params.initial(avatar, o.damping);
  VecX x = res.initial;
  VecX lower, upper;
  params.bounds(lower, upper);
  x = x.cwiseMax(lower).cwiseMin(upper);

  SharedRun shared(avatar, params, bones, fit_steps, vertices, o);
  ceres::Problem::Options po;
  po.cost_function_ownership = ceres::TAKE_OWNERSHIP;
  po.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(po);
  const std::unique_ptr<ceres::LossFunction> loss = make_loss(o);
  add_vertex_blocks(problem, shared, frames, vertices, observed, P, VecX(), loss.get(), {x.data()});
  for (int i = 0; i < P; ++i) {
    problem.SetParameterLowerBound(x.data(), i, lower[i]);
    problem.SetParameterUpperBound(x.data(), i, upper[i]);
  }
  res.residuals = problem.NumResiduals();

  ProgressLog progress(o.log);
  const ceres::Solver::Options so = solver_options(o, &progress);
  ceres::Solver::Summary summary;
  const std::clock_t cpu0 = std::clock();
  Timer wall;
  ceres::Solve(so, &problem, &summary);
  res.seconds = wall.seconds();
  res.cpu_seconds = double(std::clock() - cpu0) / CLOCKS_PER_SEC;
  res.fitted = x;
  res.brief_report = summary.BriefReport();
  res.termination = summary.message;
  {
    char buf[200];
    std::snprintf(buf, sizeof buf, "residual evaluations %.2f s, Jacobian evaluations %.2f s, linear solver %.2f s",
                  summary.residual_evaluation_time_in_seconds, summary.jacobian_evaluation_time_in_seconds,
                  summary.linear_solver_time_in_seconds);
    res.ceres_seconds = buf;
  }
  res.converged = summary.termination_type == ceres::CONVERGENCE;
  res.iterations = summary.num_successful_steps + summary.num_unsuccessful_steps;
  res.initial_cost = summary.initial_cost;
  res.final_cost = summary.final_cost;
  res.simulations = shared.simulations;
  res.jacobian_simulations = shared.jacobian_simulations;
  res.ms_per_jacobian = shared.jacobian_simulations ? shared.ms_jacobian / shared.jacobian_simulations : 0;
  res.ms_per_simulation = shared.plain_simulations ? shared.ms_plain / shared.plain_simulations : 0;

  // Uncertainty: Ceres' Gauss–Newton covariance (JᵀJ)⁻¹ scaled by the residual variance.
  res.std_error = VecX::Constant(P, std::numeric_limits<double>::quiet_NaN());
  {
    ceres::Covariance::Options co;
    co.algorithm_type = ceres::DENSE_SVD;
    co.null_space_rank = -1;
    co.min_reciprocal_condition_number = 1e-14;
    ceres::Covariance cov(co);
    const std::vector<std::pair<const double*, const double*>> blocks = {{x.data(), x.data()}};
    if (cov.Compute(blocks, &problem)) {
      Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> C(P, P);
      cov.GetCovarianceBlock(x.data(), x.data(), C.data());
      const double dof = std::max(1, res.residuals - P);
      const double sigma2 = 2.0 * summary.final_cost / dof;
      for (int i = 0; i < P; ++i) res.std_error[i] = std::sqrt(std::max(0.0, C(i, i) * sigma2));
    } else {
      res.warnings.push_back("Ceres could not compute the covariance (the Jacobian is rank deficient)");
    }
  }
  // Identifiability: the final Jacobian's singular values and weak directions.
  {
    const SurfaceRun& run = shared.get(x.data(), true);
    MatX JtJ = MatX::Zero(P, P);
    for (const MatX& J : run.jacobian) JtJ.noalias() += J.transpose() * J;
    Eigen::SelfAdjointEigenSolver<MatX> eig(JtJ);
    const VecX lambda = eig.eigenvalues().cwiseMax(0.0);  // increasing
    res.singular_values = lambda.reverse().cwiseSqrt();
    const double smax = res.singular_values.size() ? res.singular_values[0] : 0;
    for (int k = 0; k < P; ++k) {
      const double s = std::sqrt(lambda[k]);
      if (smax > 0 && s > 1e-4 * smax) break;
      std::ostringstream w;
      w << "warning: the motion does not identify";
      const VecX v = eig.eigenvectors().col(k);
      for (int i = 0; i < P; ++i)
        if (std::abs(v[i]) > 0.3) w << " " << res.labels[i];
      w << " (singular value " << s << " vs largest " << smax << "; these move the skin by < 1e-4 of the best-identified direction)";
      res.warnings.push_back(w.str());
    }
    for (int i = 0; i < P; ++i)
      if (is_log(params.entries()[i]) && res.std_error[i] > 0.5)
        res.warnings.push_back("warning: " + res.labels[i] + " is poorly identified (1-sigma factor " +
                               sigma_factor(res.std_error[i]) + ")");
  }
  res.materials = params.materials(avatar.materials, x);
  res.damping = params.damping(x, o.damping);

  // Per-frame error over every vertex, before and after.
  const SurfaceRun before = simulate_surface(avatar, params, res.initial, o.damping, bones, steps, {}, false);
  const SurfaceRun after = simulate_surface(avatar, params, x, o.damping, bones, steps, {}, false);
  res.frame_rms_before = frame_rms(before, observed);
  res.frame_rms_after = frame_rms(after, observed);
  for (int s : steps) res.frame_time.push_back(s * bones.h);
  res.rms_before = total_rms(res.frame_rms_before);
  res.rms_after = total_rms(res.frame_rms_after);
  return res;
}

std::string MaterialFitResult::describe() const {
  std::ostringstream o;
  o << std::setprecision(4);
  o << "fitted parameters (±1 sigma from the Gauss-Newton covariance):\n";
  for (size_t i = 0; i < labels.size(); ++i) {
    const bool log = labels[i].rfind("young:", 0) == 0 || labels[i].rfind("fung_c:", 0) == 0;
    char buf[200];
    if (log && std_error[i] > std::log(10.0))
      std::snprintf(buf, sizeof buf, "  %-22s x%-8.4f (start x%.4f)  1-sigma factor %s\n", labels[i].c_str(),
                    std::exp(fitted[i]), std::exp(initial[i]), sigma_factor(std_error[i]).c_str());
    else if (log)
      std::snprintf(buf, sizeof buf, "  %-22s x%-8.4f (start x%.4f)  ±%.2f%%\n", labels[i].c_str(), std::exp(fitted[i]),
                    std::exp(initial[i]), 100 * (std::exp(std_error[i]) - 1));
    else
      std::snprintf(buf, sizeof buf, "  %-22s %-9.5g (start %.5g)  ±%.3g\n", labels[i].c_str(), fitted[i], initial[i],
                    std_error[i]);
    o << buf;
  }
  o << "singular values of J:";
  for (int i = 0; i < singular_values.size(); ++i) o << " " << singular_values[i];
  o << "\n";
  for (const std::string& w : warnings) o << w << "\n";
  const double per_coordinate = 1.0 / std::sqrt(3.0);
  o << std::fixed << std::setprecision(3) << "surface error RMS per coordinate: " << rms_before * per_coordinate * 1e3
    << " mm before, " << rms_after * per_coordinate * 1e3 << " mm after (vertex distance RMS " << rms_before * 1e3
    << " -> " << rms_after * 1e3 << " mm; " << frame_time.size() << " frames, every vertex)\n";
  o << "time: " << seconds << " s wall, " << cpu_seconds << " s CPU; " << iterations << " iterations ("
    << (iterations ? seconds / iterations : 0.0) << " s each); " << simulations << " simulations, "
    << jacobian_simulations << " with Jacobians; " << ms_per_simulation << " ms per run without, " << ms_per_jacobian
    << " ms per Jacobian evaluation; Ceres: " << ceres_seconds << "\n";
  return o.str();
}

void write_fit_error_svg(const MaterialFitResult& r, const std::string& path, const std::string& title) {
  const double W = 800, H = 420, L = 70, R = 20, T = 45, B = 55;
  const double t0 = r.frame_time.empty() ? 0 : r.frame_time.front();
  const double t1 = r.frame_time.empty() ? 1 : std::max(r.frame_time.back(), t0 + 1e-9);
  double ymax = 1e-6;
  for (double v : r.frame_rms_before) ymax = std::max(ymax, v * 1e3);
  for (double v : r.frame_rms_after) ymax = std::max(ymax, v * 1e3);
  const double step = std::pow(10, std::floor(std::log10(ymax)));
  ymax = std::ceil(ymax / step) * step;
  auto X = [&](double t) { return L + (t - t0) / (t1 - t0) * (W - L - R); };
  auto Y = [&](double v) { return H - B - v / ymax * (H - T - B); };
  io::write_text_file(path, [&](std::ostream& f) {
    f << "<svg xmlns='http://www.w3.org/2000/svg' width='" << W << "' height='" << H
      << "' font-family='sans-serif' font-size='12'>\n<rect width='100%' height='100%' fill='white'/>\n";
    f << "<text x='" << W / 2 << "' y='24' text-anchor='middle' font-size='15'>" << title << "</text>\n";
    for (double v = 0; v <= ymax + 1e-12; v += step)
      f << "<line x1='" << L << "' y1='" << Y(v) << "' x2='" << W - R << "' y2='" << Y(v) << "' stroke='#ddd'/><text x='"
        << L - 6 << "' y='" << Y(v) + 4 << "' text-anchor='end'>" << v << "</text>\n";
    f << "<rect x='" << L << "' y='" << T << "' width='" << W - L - R << "' height='" << H - T - B
      << "' fill='none' stroke='black'/>\n";
    f << "<text x='" << (L + W - R) / 2 << "' y='" << H - 15 << "' text-anchor='middle'>time (s); " << t0 << " to " << t1
      << "</text>\n";
    f << "<text transform='translate(20," << (T + H - B) / 2
      << ") rotate(-90)' text-anchor='middle'>surface error RMS per frame (mm)</text>\n";
    auto series = [&](const std::vector<double>& v, const char* color, const char* label, int row) {
      f << "<polyline fill='none' stroke='" << color << "' stroke-width='2' points='";
      for (size_t i = 0; i < v.size(); ++i) f << X(r.frame_time[i]) << "," << Y(v[i] * 1e3) << " ";
      f << "'/>\n<text x='" << W - R - 10 << "' y='" << T + 18 * row << "' text-anchor='end' fill='" << color << "'>"
        << label << "</text>\n";
    };
    char before[80], after[80];
    std::snprintf(before, sizeof before, "before the fit (RMS %.2f mm)", r.rms_before * 1e3);
    std::snprintf(after, sizeof after, "after the fit (RMS %.2f mm)", r.rms_after * 1e3);
    series(r.frame_rms_before, "#d62728", before, 1);
    series(r.frame_rms_after, "#1f77b4", after, 2);
    f << "</svg>\n";
  });
}

}  // namespace sflsh
