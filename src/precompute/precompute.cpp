#include "sflsh/precompute/precompute.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iomanip>
#include <sstream>

#include "sflsh/body/body_model_io.hpp"
#include "sflsh/core/child_processes.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/core/fnv_hash.hpp"
#include "sflsh/core/memory.hpp"
#include "sflsh/core/progress.hpp"
#include "sflsh/core/timer.hpp"
#include "sflsh/io/input_file.hpp"
#include "sflsh/fem/tet_operators.hpp"

namespace sflsh {

// Revision of the meshing code whose output a cached template holds; bumped
// when a fix changes the mesh for the same options, so that stale cache
// entries (and batch outputs keyed on them) are rebuilt rather than reused.
// 2: SurfaceQuery's edge pseudo-normals zero-initialized (2026-11-26; before,
// heap garbage could flip the shell's inside test, scripts/results/cgal_hang.md).
constexpr int kTemplateMesherRevision = 2;

std::string template_cache_key(const BodyModel& model, const TemplateOptions& o) {
  std::ostringstream s;
  s << std::setprecision(17) << body_model_hash(model) << '|' << kTemplateVolumeFormatVersion << '|'
    << kTemplateMesherRevision << '|' << o.inner_depth
    << '|' << o.skinned_weight_threshold << '|' << o.correspondence.candidate_weight_fraction << '|'
    << o.correspondence.smoothing_iterations << '|' << o.correspondence.smoothing_lambda << '|'
    << o.mesh.facet_angle_deg << '|' << o.mesh.facet_size << '|' << o.mesh.facet_distance << '|'
    << o.mesh.cell_radius_edge_ratio << '|' << o.mesh.cell_size << '|' << o.mesh.relative_error_bound << '|'
    << o.mesh.perturb_sliver_bound_deg << '|' << o.mesh.exude_sliver_bound_deg << '|'
    << o.mesh.remove_boundary_slivers_below_deg << '|' << o.mesh.seed << '|' << o.sliver_repair.target_deg << '|'
    << o.sliver_repair.passes << '|' << o.skinned_size_scale << '|' << o.skinned_facet_distance << '|' << o.inner_facet_distance
    << "|topology," << o.topology.directions << ',' << o.topology.range << ',' << o.topology.floor_deg << ','
    << o.topology.flip_target_deg << ',' << o.topology.rounds;
  Fnv1a64 h;
  h.add(s.str());
  return h.hex();
}

namespace {

// Skin thickness at each node: distance to its skeleton point (handles go
// where the flesh is thick: belly, buttocks, thighs, ...).
VecX node_thickness(const TemplateVolume& tv, const Avatar& a) {
  const Points skeleton = tv.node_skeleton_coefficients * a.joints_rest;
  return (a.tet.nodes - skeleton).rowwise().norm();
}

VecXi dominant_bone(const MatXr& weights) {
  VecXi out(weights.rows());
  for (Eigen::Index i = 0; i < weights.rows(); ++i) weights.row(i).maxCoeff(&out[i]);
  return out;
}

VecX tet_densities(const Avatar& a) {
  VecX rho(a.tet.num_elements());
  for (int t = 0; t < rho.size(); ++t) rho[t] = a.materials[a.tet_region[t]].density;
  return rho;
}

/// Per-tet stiffness scale: the geometric-mean Young's modulus of its region (Pa).
VecX tet_moduli(const Avatar& a) {
  VecX E(a.tet.num_elements());
  for (int t = 0; t < E.size(); ++t) {
    const RegionMaterial& m = a.materials[a.tet_region[t]];
    E[t] = std::cbrt(m.young_along * m.young_through * m.young_around);
  }
  return E;
}

/// Regions the handle placement serves: those whose Simulated nodes hold at
/// least `min_fraction` of the Simulated volume (basis::allocate_handles'
/// threshold; the head's, hands' and feet's few Simulated border nodes fall
/// below it).
int simulated_region_count(const TemplateVolume& tv, double min_fraction) {
  if (tv.tet_region.size() == 0) return 1;
  const int R = 1 + tv.tet_region.maxCoeff();
  const VecXi node_region = basis::node_regions_from_tets(tv.tet, tv.tet_region, R);
  const VecX volume = fem::lumped_mass(tv.tet);
  VecX per_region = VecX::Zero(R);
  for (int i = 0; i < tv.tet.num_nodes(); ++i)
    if (tv.node_role[i] == int(NodeRole::Simulated) && node_region[i] >= 0) per_region[node_region[i]] += volume[i];
  int count = 0;
  for (int r = 0; r < R; ++r) count += per_region[r] > 0.0 && per_region[r] >= min_fraction * per_region.sum();
  return count;
}

}  // namespace

std::string default_cache_dir() {
  if (const char* d = std::getenv("SFLSH_CACHE_DIR"); d && *d) return d;
  if (const char* x = std::getenv("XDG_CACHE_HOME"); x && *x) return std::string(x) + "/sflsh";
  if (const char* home = std::getenv("HOME"); home && *home) return std::string(home) + "/.cache/sflsh";
  return (std::filesystem::temp_directory_path() / "sflsh-cache").string();
}

TemplateVolume cached_template_volume(const BodyModel& model, const PrecomputeOptions& options,
                                      PrecomputeReport* report) {
  Timer timer;
  std::string path;
  if (!options.cache_dir.empty()) {
    path = (std::filesystem::path(options.cache_dir) / ("template-" + template_cache_key(model, options.template_stage) + ".h5"))
               .string();
    if (report) report->template_cache_path = path;
    if (std::filesystem::exists(path)) {
      try {
        TemplateVolume tv = load_template_volume(path);
        if (tv.model_hash == body_model_hash(model)) {
          log_info("template stage: loaded from cache " + path);
          if (report) {
            report->template_from_cache = true;
            report->template_s = timer.seconds();
          }
          return tv;
        }
        log_info("template stage: cache entry " + path + " belongs to another model; rebuilding");
      } catch (const Error& e) {
        log_info(std::string("template stage: ignoring unreadable cache entry (") + e.what() + "); rebuilding");
      }
    }
  }
  TemplateVolume tv = build_template_volume(model, options.template_stage);
  if (!path.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(options.cache_dir, ec);
    if (ec) fail("cannot create cache folder ", options.cache_dir, ": ", ec.message());
    // Parallel jobs may build the same entry at once: each writes a name of
    // its own and renames it into place (atomic; identical contents).
    const std::string mine = path + "." + process_tag() + ".tmp";
    save_template_volume(tv, mine);
    std::filesystem::rename(mine, path, ec);
    if (ec) fail("cannot move ", mine, " to ", path, ": ", ec.message());
  }
  if (report) {
    report->template_report = tv.report;
    report->template_s = timer.seconds();
  }
  return tv;
}

Avatar precompute_shape(const TemplateVolume& tv, const BodyModel& model, const VecX& betas,
                        const PrecomputeOptions& options, PrecomputeReport* report) {
  PrecomputeReport local;
  PrecomputeReport& r = report ? *report : local;
  Timer total;
  require(options.bbw.support_radius >= 0.0 && std::isfinite(options.bbw.support_radius),
          "precompute: support radius must be a positive length in metres (or 0 for none), got ",
          options.bbw.support_radius);
  require(options.bbw.support_spacing_factor >= 0.0 && std::isfinite(options.bbw.support_spacing_factor),
          "precompute: support spacing factor must be positive (or 0 for none), got ",
          options.bbw.support_spacing_factor);
  if ((options.bbw.support_radius > 0.0 || options.bbw.support_spacing_factor > 0.0) &&
      options.handle_positions.rows() == 0) {
    // Compact supports reach only their own neighbourhood: a region without a
    // handle would get no soft tissue at all.
    const int regions = simulated_region_count(tv, options.placement.min_region_fraction);
    require(options.handles >= regions, "precompute: --handles ", options.handles, " is below the ", regions,
            " simulated regions; with compact supports (--support-radius, --support-spacing) every region needs a "
            "handle");
  }

  Timer t;
  ShapedVolume shaped = shape_volume(tv, model, betas, options.thickness, options.shape_stage);
  r.shape_report = shaped.report;
  r.shape_geometry_s = t.seconds();
  Avatar a = std::move(shaped.avatar);
  a.betas = betas;
  a.model_hash = body_model_hash(model);
  a.model_source = model.source;

  t.reset();
  const int num_regions = int(a.materials.size());
  const VecXi node_region = basis::node_regions_from_tets(a.tet, a.tet_region, num_regions);
  basis::HandleSet handles = options.handle_positions.rows() > 0
                                 ? basis::snap_handles(a.tet, a.node_role, options.handle_positions)
                                 : basis::select_handles(a.tet, a.node_role, options.handles, node_thickness(tv, a),
                                                         node_region, options.placement);
  a.handles = handles.positions;
  r.handles_s = t.seconds();

  t.reset();
  a.W = basis::bounded_biharmonic_weights(a.tet, a.node_role, handles.nodes, options.bbw, &r.bbw_report);
  r.weights_s = t.seconds();
  r.coverage = basis::basis_coverage(a.W, a.node_role, a.surface_nodes, node_region, num_regions, handles.nodes);
  r.region_names.clear();
  for (const RegionMaterial& m : a.materials) r.region_names.push_back(m.name);

  t.reset();
  // Inertia: data-oblivious cubature (Tapia et al. 2021), samples at the
  // handles plus one per bone region. Elasticity: stratified samples where the
  // strain lives (see basis::stratified_cubature for why the handle samples
  // alone under-integrate it).
  const VecXi bone = dominant_bone(a.node_weights);
  a.inertia = basis::data_oblivious_cubature(a.tet, a.W, handles.nodes, bone);
  a.elastic = options.elastic_samples_per_cell > 0
                  ? basis::stratified_cubature(a.tet, a.W, bone, options.elastic_samples_per_cell)
                  : a.inertia;
  if (options.fit_elastic_cubature)
    a.elastic = basis::stiffness_fitted_cubature(a.tet, a.W, a.node_role, a.elastic, tet_moduli(a), &r.elastic_fit);
  const VecX rho = tet_densities(a);
  if (options.inertia_samples_per_cell > 0)
    a.inertia = basis::mass_fitted_cubature(a.tet, a.W, a.node_role, a.node_weights, rho,
                                            options.inertia_samples_per_cell, &r.inertia_fit);
  r.elastic_errors = basis::cubature_errors(a.tet, a.elastic, rho);
  r.inertia_errors = basis::cubature_errors(a.tet, a.inertia, rho);
  r.elastic_handles = basis::handles_per_sample(a.tet, a.W, a.node_role, a.elastic);
  r.inertia_handles = basis::handles_per_sample(a.tet, a.W, a.node_role, a.inertia);
  r.cubature_s = t.seconds();
  r.shape_stage_s = total.seconds();
  r.peak_rss_mib = peak_rss_mib();
  return a;
}

Avatar precompute_avatar(const BodyModel& model, const VecX& betas, const PrecomputeOptions& options,
                         PrecomputeReport* report) {
  PrecomputeReport local;
  PrecomputeReport& r = report ? *report : local;
  TemplateVolume tv = cached_template_volume(model, options, &r);
  return precompute_shape(tv, model, betas, options, &r);
}

Points read_handles_file(const std::string& path) {
  io::require_input_file(path, "handles file");
  std::ifstream in(path);
  if (!in) fail(path, ": cannot open handles file");
  std::vector<Vec3> pts;
  std::string line;
  int lineno = 0;
  while (std::getline(in, line)) {
    ++lineno;
    if (auto c = line.find('#'); c != std::string::npos) line.resize(c);
    for (auto& ch : line)
      if (ch == ',' || ch == '\t' || ch == '\r') ch = ' ';
    std::istringstream ls(line);
    double v[3];
    int n = 0;
    std::string tok;
    while (ls >> tok) {
      if (n == 3) fail(path, ":", lineno, ": expected 3 numbers (x y z in metres), found more");
      char* end = nullptr;
      v[n] = std::strtod(tok.c_str(), &end);
      if (end == tok.c_str() || *end != '\0' || !std::isfinite(v[n]))
        fail(path, ":", lineno, ": '", tok, "' is not a finite number");
      ++n;
    }
    if (n == 0) continue;
    if (n != 3) fail(path, ":", lineno, ": expected 3 numbers (x y z in metres), found ", n);
    pts.emplace_back(v[0], v[1], v[2]);
  }
  if (pts.empty()) fail(path, ": no handle positions found");
  Points P(pts.size(), 3);
  for (size_t i = 0; i < pts.size(); ++i) P.row(i) = pts[i];
  return P;
}

std::string PrecomputeReport::describe() const {
  std::ostringstream o;
  o << std::fixed << std::setprecision(2);
  o << "timings: template stage " << template_s << " s" << (template_from_cache ? " (from cache)" : "")
    << ", shape stage " << shape_stage_s << " s (geometry " << shape_geometry_s << " s, handles " << handles_s
    << " s, weights " << weights_s << " s, cubature " << cubature_s << " s), peak memory " << peak_rss_mib << " MiB\n";
  if (!template_from_cache) o << template_report.describe() << "\n";
  o << shape_report.describe() << "\n" << bbw_report.summary() << "\n";
  if (bbw_report.support_radius > 0)
    o << "compact support: largest radius " << bbw_report.support_radius << " m along the tet edges, largest support "
      << bbw_report.max_support_nodes << " nodes\n";
  for (const auto* h : {&elastic_handles, &inertia_handles})
    if (h->samples > 0)
      o << "handles per " << (h == &elastic_handles ? "elastic" : "inertia") << " sample: mean " << h->mean
        << ", max " << h->max << " (" << h->samples << " samples)\n";
  // (coverage: printed by the avatar summary, see summarize_avatar.)
  o << std::setprecision(3);
  // CubatureErrors holds relative errors already.
  auto pct = [](double rel_err) { return 100.0 * std::abs(rel_err); };
  for (const auto* c : {&elastic_errors, &inertia_errors})
    o << (c == &elastic_errors ? "elastic" : "inertia") << " cubature vs. full integration (relative): volume "
      << pct(c->volume_error) << " %, mass " << pct(c->mass_error) << " %, quadratic field |x - c|^2 "
      << pct(c->quadratic_error) << " %\n";
  if (elastic_fit.candidates > 0)
    o << "elastic cubature fitted to the basis stiffness: " << elastic_fit.samples << " of " << elastic_fit.candidates
      << " candidate tets kept, stiffness-tensor error " << pct(elastic_fit.stiffness_error_initial) << " % -> "
      << pct(elastic_fit.stiffness_error) << " % (" << elastic_fit.sweeps << " sweeps)\n";
  if (inertia_fit.candidates > 0)
    o << "inertia cubature fitted to the lumped mass matrix: " << inertia_fit.samples << " of "
      << inertia_fit.candidates << " candidate nodes kept, " << inertia_fit.moments << " mass moments, error "
      << pct(inertia_fit.moment_error_initial) << " % -> " << pct(inertia_fit.moment_error) << " %, mass "
      << inertia_fit.mass << " kg (" << pct(inertia_fit.mass_error) << " % off, " << inertia_fit.sweeps << " sweeps)\n";
  return o.str();
}

}  // namespace sflsh
