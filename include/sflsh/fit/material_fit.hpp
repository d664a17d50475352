#pragma once
// Fitting per-region material parameters to observed skin motion with Ceres.
// Residuals: simulated minus observed surface vertex positions
// (m), one 3-residual block per (observed frame, vertex) so a robust loss acts
// per vertex; every block reads one shared simulation of the current
// parameters (trajectory_sensitivity.hpp), whose forward sensitivities are the
// blocks' analytic Jacobians. Ceres' Levenberg–Marquardt with bounds does the
// optimization; Ceres' Covariance gives the fitted values' uncertainty.
#include <functional>
#include <string>
#include <vector>

#include "sflsh/asset/avatar.hpp"
#include "sflsh/fit/fit_parameters.hpp"
#include "sflsh/fit/trajectory_sensitivity.hpp"

namespace sflsh {

struct MaterialFitOptions {
  int vertex_stride = 1;      ///< residuals on every n-th surface vertex
  int frame_stride = 1;       ///< residuals on every n-th observed frame
  std::string loss = "none";  ///< "none", "huber" or "cauchy"
  double loss_scale = 0.003;  ///< m: residual norm where the robust loss bends
  bool numeric = false;       ///< Jacobians by central differences of whole runs (2 runs per parameter)
  double numeric_step = 1e-4; ///< their step in the parameter's units
  int max_iterations = 30;    ///< Ceres iterations
  double function_tolerance = 1e-6;  ///< Ceres: stop when |Δcost|/cost falls below
  double damping = 0.0;       ///< β (s) when damping is not estimated
  /// Called with one line per Ceres iteration (progress); may be empty.
  std::function<void(const std::string&)> log;
};

struct MaterialFitResult {
  std::vector<std::string> labels;  ///< per parameter (FitParameter::label)
  VecX initial, fitted;             ///< parameter values (log factors, ν, β)
  VecX std_error;                   ///< one standard deviation from the Gauss–Newton covariance (NaN if unavailable)
  VecX singular_values;             ///< of the final Jacobian (sqrt of JᵀJ's eigenvalues), decreasing
  std::vector<std::string> warnings;  ///< unidentified parameters and the like, one line each
  std::vector<RegionMaterial> materials;  ///< fitted
  double damping = 0;                     ///< fitted (or the fixed) β, s
  std::string brief_report, termination;  ///< Ceres' Summary::BriefReport() and its message
  std::string ceres_seconds;              ///< where Ceres' time went (residuals, Jacobians, linear solver)
  bool converged = false;
  int iterations = 0;
  double initial_cost = 0, final_cost = 0;  ///< Ceres cost ½ Σ ρ(|r|²) (m²)
  double seconds = 0, cpu_seconds = 0;      ///< total wall and process CPU time of the solve
  int simulations = 0;            ///< forward runs (numeric: 2 per parameter per Jacobian, counted here too)
  int jacobian_simulations = 0;   ///< Jacobian evaluations
  /// Wall time of one run without the Jacobian, and of one Jacobian evaluation
  /// (analytic: the run with sensitivities; numeric: the 2·#p extra runs).
  double ms_per_simulation = 0, ms_per_jacobian = 0;
  int residuals = 0;
  /// RMS over all vertices of the simulated-to-observed distance (m) per
  /// observed frame, with the initial and the fitted parameters (per
  /// coordinate: divide by √3).
  std::vector<double> frame_time, frame_rms_before, frame_rms_after;
  double rms_before = 0, rms_after = 0;  ///< over every frame and vertex (m)
  std::string describe() const;  ///< the fitted values with their uncertainty, warnings, errors
};

/// Fits `params` of `avatar` so that simulating `bones` reproduces the
/// observed surfaces `observed` (#V by 3 each) at steps `steps` (increasing).
MaterialFitResult fit_materials(const Avatar& avatar, const FitParameters& params, const BoneSequence& bones,
                                const std::vector<int>& steps, const std::vector<Points>& observed,
                                const MaterialFitOptions& options);

/// Writes the per-frame RMS surface error before and after the fit (mm) as an SVG line plot.
void write_fit_error_svg(const MaterialFitResult& result, const std::string& path, const std::string& title);

}  // namespace sflsh
