#include "sflsh/fit/shape_map.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>

#include "fit/fit_problem.hpp"
#include "sflsh/io/atomic_output.hpp"
#include "sflsh/scene/yaml_document.hpp"
#include "sflsh/sim/elastic_sensitivity.hpp"

namespace sflsh {
namespace {

using namespace fit_detail;

/// sqrt(λ) P_k: the regularizer's residuals (#p) on one block.
class RegularizerCost : public ceres::CostFunction {
 public:
  RegularizerCost(int n, double weight) : n_(n), w_(weight) {
    set_num_residuals(n);
    mutable_parameter_block_sizes()->push_back(n);
  }
  bool Evaluate(double const* const* x, double* r, double** J) const override {
    for (int i = 0; i < n_; ++i) r[i] = w_ * x[0][i];
    if (J && J[0])
      for (int i = 0; i < n_; ++i)
        for (int j = 0; j < n_; ++j) J[0][i * n_ + j] = i == j ? w_ : 0.0;
    return true;
  }

 private:
  int n_;
  double w_;
};

VecX padded(const VecX& b, int n) {
  VecX out = VecX::Zero(n);
  for (int k = 0; k < std::min<int>(n, int(b.size())); ++k) out[k] = b[k];
  return out;
}

double rms(const SurfaceRun& run, const std::vector<Points>& observed) {
  double s = 0;
  long n = 0;
  for (size_t f = 0; f < observed.size(); ++f) {
    s += (run.surface[f] - observed[f]).rowwise().squaredNorm().sum();
    n += observed[f].rows();
  }
  return std::sqrt(s / std::max(1L, n));
}

struct MapSolve {
  ShapeMap map;
  ceres::Solver::Summary summary;
  double cpu_seconds = 0;
};

/// The joint fit over `subjects` except `skip` (−1: none).
MapSolve solve_map(const std::vector<FitSubject>& subjects, const FitParameters& params, const MaterialFitOptions& o,
                   double lambda, int num_betas, int skip, const VecX& start_p0, const MatX& start_pk) {
  const int P = params.size();
  MapSolve out;
  out.map.p0 = start_p0;
  out.map.pk = start_pk;
  std::vector<VecX> pk(num_betas);
  for (int k = 0; k < num_betas; ++k) pk[k] = start_pk.col(k);
  ceres::Problem::Options po;
  po.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(po);
  const std::unique_ptr<ceres::LossFunction> loss = make_loss(o);
  std::vector<double*> blocks = {out.map.p0.data()};
  for (VecX& b : pk) blocks.push_back(b.data());
  std::vector<std::unique_ptr<SharedRun>> runs;
  std::vector<std::vector<int>> steps(subjects.size());
  for (size_t s = 0; s < subjects.size(); ++s) {
    if (int(s) == skip) continue;
    const FitSubject& sub = subjects[s];
    const std::vector<int> frames = strided(int(sub.steps.size()), o.frame_stride);
    const std::vector<int> vertices = strided(int(sub.avatar->surface_rest.rows()), o.vertex_stride);
    for (int f : frames) steps[s].push_back(sub.steps[f]);
    runs.push_back(std::make_unique<SharedRun>(*sub.avatar, params, sub.bones, steps[s], vertices, o));
    add_vertex_blocks(problem, *runs.back(), frames, vertices, sub.observed, P, padded(sub.avatar->betas, num_betas),
                      loss.get(), blocks);
  }
  for (int k = 0; k < num_betas; ++k)
    problem.AddResidualBlock(new RegularizerCost(P, std::sqrt(lambda)), nullptr, pk[k].data());
  VecX lower, upper;
  params.bounds(lower, upper);
  for (int i = 0; i < P; ++i) {
    problem.SetParameterLowerBound(out.map.p0.data(), i, lower[i]);
    problem.SetParameterUpperBound(out.map.p0.data(), i, upper[i]);
  }
  ProgressLog progress(o.log);
  const ceres::Solver::Options so = solver_options(o, &progress);
  const std::clock_t cpu0 = std::clock();
  ceres::Solve(so, &problem, &out.summary);
  out.cpu_seconds = double(std::clock() - cpu0) / CLOCKS_PER_SEC;
  for (int k = 0; k < num_betas; ++k) out.map.pk.col(k) = pk[k];
  return out;
}

}  // namespace

VecX ShapeMap::evaluate(const VecX& betas) const {
  for (int k = int(pk.cols()); k < betas.size(); ++k)
    require(betas[k] == 0, "shape map: betas[", k, "] = ", betas[k], " but the map has only ", pk.cols(), " shape terms");
  return p0 + pk * padded(betas, int(pk.cols()));
}

ShapeMapResult fit_shape_map(const std::vector<FitSubject>& subjects, const FitParameters& params,
                             const MaterialFitOptions& o, double lambda, bool leave_one_out) {
  require(subjects.size() >= 2, "fit --dataset: need at least 2 subjects, got ", subjects.size());
  require(std::isfinite(lambda) && lambda >= 0, "--regularization must be >= 0, got ", lambda);
  const Avatar& first = *subjects[0].avatar;
  int num_betas = 0;
  for (const FitSubject& s : subjects) {
    require(s.avatar->tet.num_elements() == first.tet.num_elements() && s.avatar->materials.size() == first.materials.size(),
            "fit --dataset: subject '", s.name, "' does not share the first subject's tet mesh and regions");
    require(s.steps.size() == s.observed.size() && !s.steps.empty(), "fit --dataset: subject '", s.name,
            "' has no observed frames");
    num_betas = std::max(num_betas, int(s.avatar->betas.size()));
  }
  const int P = params.size();
  ShapeMapResult res;
  for (const FitParameter& e : params.entries()) res.map.labels.push_back(e.label(first.materials));
  const VecX p_start = params.initial(first, o.damping);
  const Timer wall;
  MapSolve full = solve_map(subjects, params, o, lambda, num_betas, -1, p_start, MatX::Zero(P, num_betas));
  res.map.p0 = full.map.p0;
  res.map.pk = full.map.pk;
  res.brief_report = full.summary.BriefReport();
  res.termination = full.summary.message;
  res.iterations = full.summary.num_successful_steps + full.summary.num_unsuccessful_steps;
  res.cpu_seconds = full.cpu_seconds;
  for (const FitSubject& s : subjects) {
    res.rms_before.push_back(rms(simulate_surface(*s.avatar, params, p_start, o.damping, s.bones, s.steps, {}, false),
                                 s.observed));
    res.rms_after.push_back(rms(simulate_surface(*s.avatar, params, res.map.evaluate(s.avatar->betas), o.damping,
                                                 s.bones, s.steps, {}, false),
                                s.observed));
  }
  if (leave_one_out) {
    MaterialFitOptions quiet = o;
    quiet.log = nullptr;
    for (size_t i = 0; i < subjects.size(); ++i) {
      const MapSolve loo = solve_map(subjects, params, quiet, lambda, num_betas, int(i), res.map.p0, res.map.pk);
      res.cpu_seconds += loo.cpu_seconds;
      const FitSubject& s = subjects[i];
      res.rms_leave_one_out.push_back(rms(simulate_surface(*s.avatar, params, loo.map.evaluate(s.avatar->betas),
                                                           o.damping, s.bones, s.steps, {}, false),
                                          s.observed));
    }
  }
  res.seconds = wall.seconds();
  return res;
}

std::string ShapeMapResult::describe(const std::vector<FitSubject>& subjects) const {
  std::ostringstream o;
  o << "map p(beta) = P0 + sum_k beta_k P_k:\n";
  for (size_t i = 0; i < map.labels.size(); ++i) {
    o << "  " << std::left << std::setw(22) << map.labels[i] << " P0 " << std::setw(10) << map.p0[i];
    for (int k = 0; k < map.pk.cols(); ++k) o << "  P" << k + 1 << " " << map.pk(i, k);
    o << "\n";
  }
  o << std::fixed << std::setprecision(3) << "surface error RMS per subject (mm, vertex distance): start -> map";
  if (!rms_leave_one_out.empty()) o << " (leave-one-out)";
  o << "\n";
  for (size_t s = 0; s < subjects.size(); ++s) {
    o << "  " << subjects[s].name << ": " << rms_before[s] * 1e3 << " -> " << rms_after[s] * 1e3;
    if (!rms_leave_one_out.empty()) o << " (" << rms_leave_one_out[s] * 1e3 << ")";
    o << "\n";
  }
  o << "time: " << seconds << " s wall, " << cpu_seconds << " s CPU; " << iterations << " iterations\n";
  return o.str();
}

void write_shape_map(const std::string& path, const ShapeMap& map, const std::vector<std::string>& comment) {
  io::write_text_file(path, [&](std::ostream& f) {
    f.precision(17);
    for (const std::string& c : comment) f << "# " << c << "\n";
    f << "# p(beta) = p0 + sum_k beta_k pk[k]; young/fung_c: log factors on the avatar's materials\n";
    f << "parameters:\n";
    for (size_t i = 0; i < map.labels.size(); ++i) {
      f << "  - {name: \"" << map.labels[i] << "\", p0: " << map.p0[i] << ", pk: [";
      for (int k = 0; k < map.pk.cols(); ++k) f << (k ? ", " : "") << map.pk(i, k);
      f << "]}\n";
    }
  });
}

ShapeMap read_shape_map(const std::string& path) {
  const YAML::Node root = load_yaml_file(path, "shape map");
  require(root.IsMap() && root["parameters"] && root["parameters"].IsSequence(), path,
          ": expected 'parameters:' with a list of {name, p0, pk}");
  const YAML::Node ps = root["parameters"];
  ShapeMap m;
  m.p0.resize(ps.size());
  int nb = -1;
  for (size_t i = 0; i < ps.size(); ++i) {
    const YAML::Node p = ps[i];
    require(p.IsMap() && p["name"] && p["p0"] && p["pk"] && p["pk"].IsSequence(), yaml_where(path, p),
            ": each parameter needs name, p0 and pk (a list)");
    try {
      m.labels.push_back(p["name"].as<std::string>());
      m.p0[i] = p["p0"].as<double>();
      const std::vector<double> pk = p["pk"].as<std::vector<double>>();
      if (nb < 0) nb = int(pk.size()), m.pk = MatX::Zero(ps.size(), nb);
      require(int(pk.size()) == nb, yaml_where(path, p), ": pk has ", pk.size(), " entries, the first had ", nb);
      for (int k = 0; k < nb; ++k) m.pk(i, k) = pk[k];
    } catch (const YAML::Exception&) {
      fail(yaml_where(path, p), ": name must be a string, p0 a number and pk a list of numbers");
    }
    require(std::isfinite(m.p0[i]) && m.pk.row(i).allFinite(), yaml_where(path, p), ": non-finite value");
  }
  return m;
}

std::vector<RegionMaterial> shape_map_materials(const ShapeMap& map, const Avatar& avatar, const VecX& betas,
                                                double damping, double* damping_out) {
  const VecX p = map.evaluate(betas);
  std::vector<RegionMaterial> m = avatar.materials;
  if (damping_out) *damping_out = damping;
  for (size_t i = 0; i < map.labels.size(); ++i) {
    const std::string& label = map.labels[i];
    if (label == "damping") {
      if (damping_out) *damping_out = p[i];
      continue;
    }
    const size_t colon = label.find(':');
    require(colon != std::string::npos, "shape map: parameter '", label, "' is not kind:region");
    const std::string kind = label.substr(0, colon), region = label.substr(colon + 1);
    auto it = std::find_if(m.begin(), m.end(), [&](const RegionMaterial& r) { return r.name == region; });
    require(it != m.end(), "shape map: region '", region, "' of '", label, "' is not one of the avatar's");
    if (kind == "young") {
      *it = perturbed_material(*it, MaterialParameter::LogYoung, p[i]);
    } else if (kind == "fung_c") {
      *it = perturbed_material(*it, MaterialParameter::LogFungC, p[i]);
    } else if (kind == "poisson") {
      it->poisson = p[i];
    } else {
      fail("shape map: unknown parameter kind '", kind, "' in '", label, "'");
    }
    const std::string problem = it->range_problem();
    require(problem.empty(), "shape map: region '", region, "' for these betas: ", problem);
  }
  return m;
}

}  // namespace sflsh
