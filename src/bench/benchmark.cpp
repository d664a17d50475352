#include "sflsh/bench/benchmark.hpp"

#include <malloc.h>

#include <algorithm>
#include <cmath>
#include <ctime>
#include <cstdio>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <string>

#include "sflsh/bench/bullet_peer.hpp"
#include "sflsh/bench/soft_tissue_modes.hpp"
#include "sflsh/bench/subspace_floor.hpp"
#include "sflsh/body/body_model_io.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/core/memory.hpp"
#include "sflsh/core/percentile.hpp"
#include "sflsh/core/progress.hpp"
#include "sflsh/core/timer.hpp"
#include "sflsh/fem/tet_operators.hpp"
#include "sflsh/motion/load_motion.hpp"
#include "sflsh/scene/simulation_run.hpp"
#include "sflsh/sim/energies/elastic.hpp"
#include "sflsh/reference/full_fem.hpp"
#include "sflsh/sim/posed_points.hpp"

namespace sflsh {
namespace {

constexpr double kFrameRate = 30.0;  // comparison frames per simulated second

/// Soft displacement of the skin at the comparison frames plus step timings.
struct Trace {
  std::vector<Points> u;      // per frame, #V by 3 (m)
  std::vector<double> ms;     // per step
  // Reduced runs: summed ms of the inertia and elastic terms and the solve; peak MiB added.
  double ms_inertia = 0, ms_elastic = 0, ms_solve = 0, peak_mib = std::numeric_limits<double>::quiet_NaN();
  std::vector<Points> nodal;  // reference only: per frame, #N by 3 nodal soft displacement (m)
};

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// Steps per comparison frame for time step h (h must divide 1/30 s).
int steps_per_frame(double h) {
  const double r = 1.0 / (kFrameRate * h);
  const int n = int(std::lround(r));
  require(n >= 1 && std::abs(r - n) < 1e-6, "bench: time step ", h, " s does not divide 1/", kFrameRate, " s");
  return n;
}

Trace run_reference(std::shared_ptr<const Avatar> avatar, const MotionClip& motion, double seconds, double h) {
  FullFemOptions o;
  o.h = h;
  // Errors are reported to a few significant digits: a relative gradient
  // reduction of 1e-6 per step leaves the reference far more accurate than
  // that while keeping the converged solve affordable.
  o.gradient_tolerance = 1e-6;
  FullFem fem(avatar, o);
  fem.reset(target_bones(*avatar, motion.sample(0)));
  Trace tr;
  tr.u.push_back(fem.soft_displacement());
  tr.nodal.push_back(fem.displacement());
  const int per = steps_per_frame(h);
  const long steps = std::lround(seconds / h);
  Progress p("bench: full-FEM reference", steps);
  for (long s = 1; s <= steps; ++s) {
    const FullFemReport rep = fem.step(target_bones(*avatar, motion.sample(s * h)));
    tr.ms.push_back(rep.ms_total);
    if (s % per == 0) {
      tr.u.push_back(fem.soft_displacement());
      tr.nodal.push_back(fem.displacement());
    }
    p.update(s);
  }
  p.finish();
  return tr;
}

/// Resident size now (MiB), after returning the heap's free pages to the
/// system (else a run reusing them shows no growth) and resetting the
/// process's peak (VmHWM) to it (Linux /proc/self/clear_refs "5"); NaN if
/// either is unavailable.
double reset_peak_rss_mib() {
  malloc_trim(0);
  {
    std::ofstream clear("/proc/self/clear_refs");
    if (!(clear << "5")) return kNaN;
  }
  std::ifstream f("/proc/self/status");
  std::string line;
  while (std::getline(f, line))
    if (line.rfind("VmRSS:", 0) == 0) return std::atof(line.c_str() + 6) / 1024.0;
  return kNaN;
}

/// CPU time of the calling thread (ms).
double thread_cpu_ms() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return 1e3 * double(t.tv_sec) + 1e-6 * double(t.tv_nsec);
}

Trace run_reduced(std::shared_ptr<const Avatar> avatar, const MotionClip& motion, double seconds, double h,
                  int newton_iters, const std::string& label, bool bones_dynamic = false,
                  bool mean_dilatation = SimulatorOptions().mean_dilatation,
                  std::optional<double> nonlinearity_tolerance = std::nullopt,
                  LinearSolver linear_solver = LinearSolver::Dense, bool cpu_time = false) {
  const double rss0 = reset_peak_rss_mib();
  SimulatorOptions o;
  o.newton.linear_solver = linear_solver;
  o.newton.nonlinearity_tolerance = nonlinearity_tolerance;
  o.mean_dilatation = mean_dilatation;
  o.h = h;
  o.bones_dynamic = bones_dynamic;
  o.newton.iterations = newton_iters;
  o.newton.line_search = newton_iters > 1;
  const SkeletonTermsOptions skeleton;  // dynamic bones: the skeleton terms, as `sflsh simulate`
  Simulator sim(avatar_model(avatar, o, bones_dynamic ? &skeleton : nullptr));
  sim.reset(target_bones(*avatar, motion.sample(0)));
  Trace tr;
  tr.u.push_back(sim.soft_displacement());
  const int per = steps_per_frame(h);
  const long steps = std::lround(seconds / h);
  Progress p("bench: " + label + (bones_dynamic ? " (dynamic bones)" : ""), steps);
  for (long s = 1; s <= steps; ++s) {
    const BodyPose pose = motion.sample(s * h);
    const double cpu0 = thread_cpu_ms();
    const StepReport rep = sim.step(target_bones(*avatar, pose), pose);
    const double cpu_ms = thread_cpu_ms() - cpu0;
    require(sim.state().z.allFinite(), "bench: ", label, " became non-finite at step ", s);
    tr.ms.push_back(cpu_time ? cpu_ms : rep.ms_total);
    for (const TermEnergy& e : rep.energies) {
      if (e.name == "inertia") tr.ms_inertia += e.ms;
      if (e.name == "elastic") tr.ms_elastic += e.ms;
    }
    tr.ms_solve += rep.ms_solve;
    if (s % per == 0) tr.u.push_back(sim.soft_displacement());
    p.update(s);
  }
  p.finish();
  tr.peak_mib = peak_rss_mib() - rss0;
  return tr;
}

/// The surface posed by the skeleton alone (u = 0, pose blend shapes and
/// linear blend skinning, as the simulator poses it): the cost of "doing nothing".
Trace run_skinning(const Avatar& a, const MotionClip& motion, double seconds, double h) {
  Trace tr;
  const long steps = std::lround(seconds / h);
  const int per = steps_per_frame(h);
  const Points zero = Points::Zero(a.surface_rest.rows(), 3);
  tr.u.push_back(zero);
  const PosedPoints surface = PosedPoints::at_surface(a);
  Configuration q;
  q.z = VecX::Zero(a.num_reduced());
  double checksum = 0;  // keeps the posing from being optimized away
  for (long s = 1; s <= steps; ++s) {
    Timer t;
    q.bones = target_bones(a, motion.sample(s * h));
    const Points offsets = surface_pose_offsets(a, q.bones);
    checksum += surface.world(q, &offsets)(0, 0);
    tr.ms.push_back(t.ms());
    if (s % per == 0) tr.u.push_back(zero);
  }
  require(std::isfinite(checksum), "bench: skinning produced non-finite positions");
  return tr;
}

/// Skin vertices whose embedding tet has a Simulated node.
std::vector<int> simulated_region(const Avatar& a) {
  std::vector<int> out;
  for (Eigen::Index v = 0; v < a.surface_rest.rows(); ++v) {
    const int t = a.surface_tet[v];
    for (int c = 0; c < 4; ++c)
      if (a.node_role[a.tet.elements(t, c)] == int(NodeRole::Simulated)) {
        out.push_back(int(v));
        break;
      }
  }
  return out;
}

/// The skin's soft displacement (#V by 3) interpolated from nodal values
/// (#N by 3) through (surface_tet, surface_bary), Dirichlet nodes held at 0.
Points surface_from_nodes(const Avatar& a, const Points& nodal) {
  Points u(a.surface_rest.rows(), 3);
  for (int v = 0; v < u.rows(); ++v) {
    Vec3 s = Vec3::Zero();
    for (int c = 0; c < 4; ++c) {
      const int i = a.tet.elements(a.surface_tet[v], c);
      if (a.node_role[i] == int(NodeRole::Simulated)) s += a.surface_bary(v, c) * nodal.row(i).transpose();
    }
    u.row(v) = s.transpose();
  }
  return u;
}

/// The Bullet peer on the same mesh, bones and h; skin soft displacement as
/// for the full-FEM reference (nodal u through the surface embedding). Stops
/// at the first step that inverts a tetra (*diverged_at = that step, else 0):
/// the trace then holds the frames before it.
Trace run_peer(std::shared_ptr<const Avatar> avatar, const MotionClip& motion, double seconds, double h,
               bool rest_follows_skinning, int* newton_iterations, long* diverged_at) {
  BulletPeerOptions po;
  po.h = h;
  po.rest_follows_skinning = rest_follows_skinning;
  BulletPeer peer(avatar, po);
  *newton_iterations = peer.newton_iterations();
  *diverged_at = 0;
  peer.reset(target_bones(*avatar, motion.sample(0)));
  Trace tr;
  tr.u.push_back(surface_from_nodes(*avatar, peer.soft_displacement()));
  const int per = steps_per_frame(h);
  const long steps = std::lround(seconds / h);
  Progress p(std::string("bench: Bullet peer") + (rest_follows_skinning ? " (rest re-skinned)" : ""), steps);
  for (long s = 1; s <= steps && *diverged_at == 0; ++s) {
    tr.ms.push_back(peer.step(target_bones(*avatar, motion.sample(s * h))));
    if (!(peer.min_volume_ratio() > 0)) *diverged_at = s;
    else if (s % per == 0) tr.u.push_back(surface_from_nodes(*avatar, peer.soft_displacement()));
    p.update(s);
  }
  p.finish();
  if (*diverged_at) log_info("bench: the Bullet peer inverted a tetra at step " + std::to_string(*diverged_at) + " of " + std::to_string(steps));
  return tr;
}

/// The floor trace of basis W (a.W by default): the skin displacement of the mass-weighted
/// projection of each reference frame onto span(W ⊗ I₃).
std::vector<Points> floor_trace(const Avatar& a, const Trace& ref,
                                const Eigen::SparseMatrix<double, Eigen::RowMajor>* W = nullptr) {
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

const RegionError* region_named(const BenchRow& r, const std::string& name) {
  for (const auto& g : r.regions)
    if (g.name == name) return &g;
  return nullptr;
}

}  // namespace

std::vector<BenchRow> run_benchmark(const BenchOptions& in) {
  BenchOptions o = in;
  if (o.seconds <= 0) o.seconds = o.quick ? 0.5 : 2.0;
  if (o.handle_counts.empty()) o.handle_counts = o.quick ? std::vector<int>{16} : std::vector<int>{16, 32, 64, 128};
  if (std::find(o.handle_counts.begin(), o.handle_counts.end(), o.default_handles) == o.handle_counts.end())
    o.handle_counts.push_back(o.default_handles);
  std::sort(o.handle_counts.begin(), o.handle_counts.end());

  const BodyModel model = load_body_model(o.model);
  // The motion first, on the shape's skeleton (as the avatar's), so that a bad
  // motion file fails before minutes of precompute.
  MotionOptions mo;
  mo.rest_joints = regress_joints(model, shape_vertices(model, o.betas));
  mo.builtin_seconds = o.seconds + 0.5;
  const MotionClip motion = load_motion(o.motion, mo);
  const TemplateVolume tv = cached_template_volume(model, o.precompute);
  std::vector<std::shared_ptr<const Avatar>> avatars;
  std::shared_ptr<const Avatar> default_avatar;
  for (int K : o.handle_counts) {
    PrecomputeOptions po = o.precompute;
    po.handles = K;
    log_info("bench: shape stage with K = " + std::to_string(K) + " handles");
    avatars.push_back(std::make_shared<Avatar>(precompute_shape(tv, model, o.betas, po)));
    if (K == o.default_handles) default_avatar = avatars.back();
  }
  const Avatar& base = *default_avatar;
  const std::vector<int> region = simulated_region(base);
  const VecXi labels = vertex_regions(base, region);
  const int num_regions = int(base.materials.size());
  const VecXi in_region = labels.unaryExpr([](int r) { return r >= 0 ? 0 : -1; });

  const double h = o.default_dt;
  const Trace ref = run_reference(default_avatar, motion, o.seconds, h);
  std::vector<BenchRow> rows;
  // Floors per basis (rows sharing an avatar share it; the map keeps each
  // avatar alive so that its address is never reused by another).
  std::map<std::shared_ptr<const Avatar>, std::vector<Points>> floors;
  auto floor_of = [&](const std::shared_ptr<const Avatar>& a) -> const std::vector<Points>* {
    if (!a) return nullptr;
    auto it = floors.find(a);
    if (it == floors.end()) it = floors.emplace(a, floor_trace(*a, ref)).first;
    return &it->second;
  };
  // rel_err and floor per region, and the overall floor.
  auto split = [&](const Trace& tr, const std::shared_ptr<const Avatar>& a, BenchRow& r) {
    const std::vector<Points>* fl = floor_of(a);
    r.floor_rel_err = fl ? region_rel_errors(*fl, ref.u, in_region, 1)[0] : kNaN;
    const std::vector<double> e = region_rel_errors(tr.u, ref.u, labels, num_regions);
    const std::vector<double> ef = fl ? region_rel_errors(*fl, ref.u, labels, num_regions) : std::vector<double>();
    for (int g = 0; g < num_regions; ++g)
      if (std::isfinite(e[size_t(g)])) r.regions.push_back({base.materials[size_t(g)].name, e[size_t(g)], fl ? ef[size_t(g)] : kNaN});
  };
  BenchRow rr{"reference", "full FEM, Newton to convergence", 0, h, -1, false};
  rr.ms_inertia = rr.ms_elastic = rr.ms_solve = rr.dynamic_ms_median = rr.peak_mib = kNaN;
  compare(ref, ref, region, rr);
  split(ref, nullptr, rr);
  rows.push_back(rr);
  const double ref_ms = rr.ms_median;

  auto add = [&](const Trace& tr, const std::shared_ptr<const Avatar>& a, const std::string& method, const std::string& label, int K,
                 double dt, int iters, bool is_default) {
    BenchRow r{method, label, K, dt, iters, is_default};
    r.ms_inertia = r.ms_elastic = r.ms_solve = r.dynamic_ms_median = r.peak_mib = kNaN;
    compare(tr, ref, region, r);
    split(tr, a, r);
    r.speedup = r.ms_median > 0 ? ref_ms / r.ms_median : 0;
    rows.push_back(r);
  };
  // --only: does the variant described by `what` run?
  auto wanted = [&](const std::string& what) {
    if (o.only.empty()) return true;
    for (const std::string& s : o.only)
      if (what.find(s) != std::string::npos) return true;
    return false;
  };
  auto reduced = [&](std::shared_ptr<const Avatar> a, int K, double dt, int iters, const std::string& what,
                     bool is_default, bool mean_dilatation = SimulatorOptions().mean_dilatation,
                     std::optional<double> nonlinearity_tolerance = std::nullopt) {
    const std::string label = "K=" + std::to_string(K) + (what.empty() ? "" : ", " + what);
    if (!is_default && !wanted(label)) return;
    const Trace tr = run_reduced(a, motion, o.seconds, dt, iters, "reduced " + label, false, mean_dilatation,
                                 nonlinearity_tolerance, o.linear_solver, o.cpu_time);
    add(tr, a, "reduced", label, K, dt, iters, is_default);
    BenchRow& r = rows.back();
    const double steps = double(tr.ms.size());
    r.ms_inertia = tr.ms_inertia / steps;
    r.ms_elastic = tr.ms_elastic / steps;
    r.ms_solve = tr.ms_solve / steps;
    r.peak_mib = tr.peak_mib;
    r.dynamic_ms_median =
        percentile(run_reduced(a, motion, o.seconds, dt, iters, "reduced " + label, true, mean_dilatation,
                               nonlinearity_tolerance, o.linear_solver, o.cpu_time)
                       .ms,
                   0.5);
  };
  const int K = o.default_handles;
  // Handle counts at the default time step and cubature, one Newton step
  // (plus the automatic second where a step is far off its quadratic model).
  for (size_t i = 0; i < avatars.size(); ++i)
    reduced(avatars[i], o.handle_counts[i], h, 1,
            o.handle_counts[i] != K ? "" : K == PrecomputeOptions().handles ? "default" : "default settings otherwise",
            o.handle_counts[i] == K);
  // Mean dilatation per handle cell (against the subspace's volumetric
  // locking) against every tet's own volume change, as before.
  const bool md = SimulatorOptions().mean_dilatation;
  reduced(default_avatar, K, h, 1, md ? "volume per tet (no mean dilatation, before)" : "mean dilatation", false, !md);
  // Time steps and Newton iterations around the default.
  for (double dt : o.quick ? std::vector<double>{1.0 / 30.0} : std::vector<double>{1.0 / 30.0, 1.0 / 120.0})
    reduced(default_avatar, K, dt, 1, "dt=1/" + std::to_string(int(std::lround(1.0 / dt))), false);
  // Fixed iteration counts (no nonlinearity check), against the default's
  // one step plus one more where it is > 5 % off its quadratic model.
  for (int iters : {1, 2, 3})
    reduced(default_avatar, K, h, iters,
            iters == 1 ? "one Newton step, no nonlinearity check (before)" : std::to_string(iters) + " Newton iterations",
            false, md, 0.0);
  reduced(default_avatar, K, h, o.converged_newton_iters, "Newton converged", false, md, 0.0);
  // Cubature variants: the stratified samples without the stiffness fit, more
  // or fewer candidates, and exact integration (one sample per tet) for the
  // elastic energy alone and for elasticity and inertia: the error of the basis itself.
  auto cubature_variant = [&](int per_cell, bool fit, const std::string& what) {
    PrecomputeOptions po = o.precompute;
    po.handles = K;
    po.elastic_samples_per_cell = per_cell;
    po.fit_elastic_cubature = fit;
    if (!wanted(what)) return;
    log_info("bench: shape stage for " + what);
    const auto a = std::make_shared<Avatar>(precompute_shape(tv, model, o.betas, po));
    reduced(a, K, h, 1, what + " (" + std::to_string(a->elastic.size()) + " samples)", false);
  };
  // The earlier basis (bones Dirichlet 0 in every QP), for its floor
  // and its simulation next to the default's.
  if (wanted("bones Dirichlet 0") || wanted("bones depth-blended")) {
    PrecomputeOptions po = o.precompute;
    po.handles = K;
    po.bbw.bone_condition = po.bbw.bone_condition == basis::BoneCondition::Dirichlet ? basis::BoneCondition::DepthBlend
                                                                                     : basis::BoneCondition::Dirichlet;
    const bool dirichlet = po.bbw.bone_condition == basis::BoneCondition::Dirichlet;
    log_info("bench: shape stage with bones " + std::string(dirichlet ? "Dirichlet" : "depth-blended"));
    const auto a = std::make_shared<Avatar>(precompute_shape(tv, model, o.betas, po));
    reduced(a, K, h, 1, dirichlet ? "bones Dirichlet 0 (the earlier basis)" : "bones depth-blended", false);
  }
  // Handle allocation ("handle placement"): more handles for the
  // small regions (calf, arms, neck, chest) at the same K, taken from the
  // large ones by the same apportionment.
  for (int m : {2, 4, 6}) {
    const std::string what =
        "at least " + std::to_string(m) + " handles per region" + (m == 2 ? " (the earlier minimum)" : "");
    if (m == o.precompute.placement.min_per_region || !wanted(what)) continue;
    PrecomputeOptions po = o.precompute;
    po.handles = K;
    po.placement.min_per_region = m;
    log_info("bench: shape stage with " + what);
    reduced(std::make_shared<Avatar>(precompute_shape(tv, model, o.betas, po)), K, h, 1, what, false);
  }
  const PrecomputeOptions defaults = o.precompute;
  cubature_variant(defaults.elastic_samples_per_cell, !defaults.fit_elastic_cubature,
                   std::string(defaults.fit_elastic_cubature ? "no" : "with") + " stiffness fit");
  if (!o.quick) {
    cubature_variant(1, true, "1 sample/cell, fitted");
    cubature_variant(6, true, "6 samples/cell, fitted");
  }
  auto exact = std::make_shared<Avatar>(base);
  if (wanted("elastic on all tets")) exact->elastic = basis::full_cubature(exact->tet, exact->node_role, true);
  reduced(exact, K, h, 1, "elastic on all tets", false);
  if (!o.quick && wanted("elastic + inertia on all tets")) {
    auto exact_both = std::make_shared<Avatar>(*exact);
    exact_both->inertia = basis::full_cubature(exact->tet);
    reduced(exact_both, K, h, 1, "elastic + inertia on all tets", false);
  }
  // The reference's own mass model (lumped at the nodes) projected onto the
  // basis: is the inertia model what separates rel_err from the floor? With
  // elasticity on all tets too, the row is the Galerkin projection of the
  // reference onto span(W ⊗ I3) up to the posing nonlinearity.
  VecX tet_density(base.tet.num_elements());
  for (int t = 0; t < base.tet.num_elements(); ++t) tet_density[t] = tet_material(base, t).density;
  if (wanted("lumped")) {
    auto lumped = std::make_shared<Avatar>(base);
    lumped->inertia = basis::nodal_cubature(base.tet, tet_density, base.node_role);
    reduced(lumped, K, h, 1, "inertia lumped at the nodes", false);
    auto lumped_exact = std::make_shared<Avatar>(*exact);
    lumped_exact->inertia = lumped->inertia;
    reduced(lumped_exact, K, h, 1, "elastic on all tets + lumped nodal inertia", false);
  }
  // The other inertia cubature: the data-oblivious samples at the handles
  // (before the mass fit), or the mass-fitted one if the default is that.
  {
    PrecomputeOptions po = o.precompute;
    po.handles = K;
    po.inertia_samples_per_cell = o.precompute.inertia_samples_per_cell > 0 ? 0 : 2;
    const std::string what = po.inertia_samples_per_cell > 0 ? "inertia mass-fitted"
                                                             : "inertia at the handles (data-oblivious, before)";
    // With both accuracy changes (mean dilatation, mass-fitted inertia) as the defaults: the setting before them.
    const std::string before = "previous default (inertia at the handles, volume per tet)";
    const bool both_default = po.inertia_samples_per_cell == 0 && SimulatorOptions().mean_dilatation;
    if (wanted(what) || (both_default && wanted(before))) {
      log_info("bench: shape stage for " + what);
      const auto a = std::make_shared<Avatar>(precompute_shape(tv, model, o.betas, po));
      const std::string label = what + " (" + std::to_string(a->inertia.size()) + " samples)";
      reduced(a, K, h, 1, label, false);
      // The combination measured: mean dilatation with the fitted inertia.
      if (po.inertia_samples_per_cell > 0 && !SimulatorOptions().mean_dilatation)
        reduced(a, K, h, 1, label + " + mean dilatation", false, true);
      if (both_default) reduced(a, K, h, 1, before, false, false);
    }
  }
  for (bool reskin : o.peer && wanted("Bullet") ? std::vector<bool>{false, true} : std::vector<bool>{}) {
    int iters = 0;
    long diverged = 0;
    const Trace tr = run_peer(default_avatar, motion, o.seconds, h, reskin, &iters, &diverged);
    std::string label = std::string("Bullet 3 Neo-Hookean FEM") + (reskin ? ", rest re-skinned" : "");
    if (diverged) label += " (diverged at step " + std::to_string(diverged) + "; error over the " + std::to_string(tr.u.size()) + " frames before)";
    add(tr, nullptr, "peer", label, 0, h, iters, false);
  }
  // Floors of a candidate basis without simulating it ("report the floor for the
  // alternatives"): a row with the floor and its regions, the simulated figures NaN.
  auto add_floor_only = [&](const std::vector<Points>& fl, const std::string& label, int handles) {
    const double nan = kNaN;
    BenchRow r{"floor", label, handles, h, 0, false};
    r.ms_median = r.ms_p95 = r.speedup = r.err_mean_mm = r.err_max_mm = r.rel_err = r.peak_ratio = nan;
    r.ms_inertia = r.ms_elastic = r.ms_solve = r.dynamic_ms_median = r.peak_mib = nan;
    r.floor_rel_err = region_rel_errors(fl, ref.u, in_region, 1)[0];
    const std::vector<double> ef = region_rel_errors(fl, ref.u, labels, num_regions);
    for (int g = 0; g < num_regions; ++g)
      if (std::isfinite(ef[size_t(g)])) r.regions.push_back({base.materials[size_t(g)].name, nan, ef[size_t(g)]});
    rows.push_back(r);
  };
  // Affine handles: 12 DoFs per handle instead of 3, on each K's handles.
  if (wanted("affine handles"))
    for (size_t i = 0; i < avatars.size(); ++i) {
      const Avatar& a = *avatars[i];
      const auto Wa = affine_handle_weights(a.W, a.tet.nodes, a.handles);
      add_floor_only(floor_trace(a, ref, &Wa),
                     "affine handles, K=" + std::to_string(a.num_handles()) + " (" +
                         std::to_string(12 * a.num_handles()) + " DoFs; floor only)",
                     a.num_handles());
    }
  // The floor trace of a general vector basis B (3N by D) on the default avatar's mesh.
  auto vector_floor_trace = [&](const MatX& B) {
    const VectorSubspaceProjector proj(B, simulated_lumped_mass(base));
    std::vector<Points> out;
    for (const Points& u : ref.nodal) out.push_back(surface_from_nodes(base, proj.project(u)));
    return out;
  };
  // Mode bases (soft_tissue_modes.hpp) as a 3N by D vector basis `modes` whose first d
  // columns are the lowest d / dofs_per_mode modes: alone, as many DoFs as each K's
  // handles, and added to the default K's handles (3K/4, 3K/2 and 3K more DoFs).
  const std::vector<int> added_dofs = {3 * K / 4, 3 * K / 2, 3 * K};
  int most_dofs = added_dofs.back();
  for (const auto& a : avatars) most_dofs = std::max(most_dofs, 3 * a->num_handles());
  auto add_mode_floors = [&](const std::string& what, const MatX& modes, int dofs_per_mode) {
    for (const auto& a : avatars) {
      const int d = 3 * a->num_handles();
      add_floor_only(vector_floor_trace(modes.leftCols(d)),
                     what + " only, " + std::to_string(d / dofs_per_mode) + " (" + std::to_string(d) +
                         " DoFs; floor only)",
                     a->num_handles());
    }
    const MatX bbw = vector_basis(base.W);
    for (int d : added_dofs) {
      d -= d % dofs_per_mode;  // whole modes
      MatX B(bbw.rows(), bbw.cols() + d);
      B << bbw, modes.leftCols(d);
      add_floor_only(vector_floor_trace(B),
                     "K=" + std::to_string(K) + " handles + " + std::to_string(d / dofs_per_mode) + " " + what +
                         " (" + std::to_string(3 * K + d) + " DoFs; floor only)",
                     K);
    }
  };
  // The lowest vibration modes of the soft tissue with the bones held: one DoF each.
  if (wanted("vibration modes")) {
    log_info("bench: the " + std::to_string(most_dofs) + " lowest vibration modes of the soft tissue (bones held)");
    add_mode_floors("vibration modes", soft_tissue_modes(base, most_dofs).phi, 1);
  }
  // Scalar skinning eigenmodes: weights like the handles' W, 3 DoFs each (column 3k + c of
  // vector_basis is mode k along axis c, so its first 3m columns are the lowest m modes).
  if (wanted("skinning eigenmodes")) {
    log_info("bench: the " + std::to_string(most_dofs / 3) + " lowest skinning eigenmodes (scalar, bones held)");
    const MatX phi = skinning_eigenmodes(base, most_dofs / 3).phi;
    add_mode_floors("skinning eigenmodes", vector_basis(phi.sparseView()), 3);
  }
  add(run_skinning(base, motion, o.seconds, h), nullptr, "skinning", "skinning only (u = 0)", 0, h, 0, false);
  return rows;
}

void write_bench_csv(const std::vector<BenchRow>& rows, const std::string& path) {
  const std::string tmp = path + ".partial";
  {
    std::ofstream f(tmp);
    if (!f) fail(path, ": cannot write");
    // Region columns follow the first row's regions (the reference lists
    // every region with reference motion; a row without one writes nan).
    const std::vector<RegionError> names = rows.empty() ? std::vector<RegionError>() : rows[0].regions;
    f << "method,handles,dt,newton_iters,is_default,ms_median,ms_p95,speedup,err_mean_mm,err_max_mm,rel_err,peak_ratio,"
         "floor_rel_err,ms_inertia,ms_elastic,ms_solve,dynamic_ms_median,peak_mib";
    for (const auto& g : names) f << ",rel_err_" << g.name << ",floor_" << g.name;
    f << "\n";
    char buf[512];
    for (const auto& r : rows) {
      std::snprintf(buf, sizeof buf, "%s,%d,%.6g,%d,%d,%.4g,%.4g,%.4g,%.4g,%.4g,%.4g,%.4g,%.4g", r.method.c_str(),
                    r.handles, r.dt, r.newton_iters, r.is_default ? 1 : 0, r.ms_median, r.ms_p95, r.speedup,
                    r.err_mean_mm, r.err_max_mm, r.rel_err, r.peak_ratio, r.floor_rel_err);
      f << buf;
      std::snprintf(buf, sizeof buf, ",%.4g,%.4g,%.4g,%.4g,%.4g", r.ms_inertia, r.ms_elastic, r.ms_solve,
                    r.dynamic_ms_median, r.peak_mib);
      f << buf;
      for (const auto& g : names) {
        const RegionError* e = region_named(r, g.name);
        std::snprintf(buf, sizeof buf, ",%.4g,%.4g", e ? e->rel_err : kNaN, e ? e->floor_rel_err : kNaN);
        f << buf;
      }
      f << "\n";
    }
    if (!f) fail(path, ": write failed");
  }
  std::rename(tmp.c_str(), path.c_str());
}

void write_bench_markdown(const std::vector<BenchRow>& rows, const std::string& path) {
  std::ofstream f(path + ".partial");
  if (!f) fail(path, ": cannot write");
  f << "| method | variant | K | dt (s) | Newton iters | ms/step median | p95 | speedup | err mean (mm) | err max (mm) "
       "| rel_err | floor | peak ratio | inertia / elastic / solve (ms) | dynamic bones ms/step | peak MiB |\n"
       "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  char buf[512];
  auto num = [](double v) {
    char b[32];
    std::snprintf(b, sizeof b, "%.3f", v);
    return std::isfinite(v) ? std::string(b) : std::string("–");
  };
  auto bold_default = [](const BenchRow& r, const std::string& line) {
    return r.is_default ? std::string(line).replace(2, r.method.size(), "**" + r.method + "**") : line;
  };
  auto ms3 = [](double v) {
    char b[32];
    std::snprintf(b, sizeof b, "%.3g", v);
    return std::isfinite(v) ? std::string(b) : std::string("–");
  };
  for (const auto& r : rows) {
    if (r.method == "floor") {  // a basis measured by its floor alone: no simulation columns
      f << "| " << r.method << " | " << r.label << " | " << r.handles << " | – | – | – | – | – | – | – | – | "
        << num(r.floor_rel_err) << " | – | – | – | – |\n";
      continue;
    }
    const std::string split = std::isfinite(r.ms_solve)
                                  ? ms3(r.ms_inertia) + " / " + ms3(r.ms_elastic) + " / " + ms3(r.ms_solve)
                                  : std::string("–");
    std::snprintf(buf, sizeof buf,
                  "| %s | %s | %d | 1/%.0f | %s | %.3g | %.3g | %.3g | %.3g | %.3g | %.3f | %s | %.3f | %s | %s | %s |\n",
                  r.method.c_str(), r.label.c_str(), r.handles, 1.0 / r.dt,
                  r.newton_iters < 0 ? "to convergence" : std::to_string(r.newton_iters).c_str(), r.ms_median,
                  r.ms_p95, r.speedup, r.err_mean_mm, r.err_max_mm, r.rel_err, num(r.floor_rel_err).c_str(),
                  r.peak_ratio, split.c_str(), ms3(r.dynamic_ms_median).c_str(), ms3(r.peak_mib).c_str());
    f << bold_default(r, buf);
  }
  // Per region: simulated rel_err / floor.
  const std::vector<RegionError> names = rows.empty() ? std::vector<RegionError>() : rows[0].regions;
  if (!names.empty()) {
    f << "\nrel_err per region (simulated / floor):\n\n| method | variant |";
    for (const auto& g : names) f << ' ' << g.name << " |";
    f << "\n|---|---|";
    for (size_t i = 0; i < names.size(); ++i) f << "---|";
    f << "\n";
    for (const auto& r : rows) {
      std::string line = "| " + r.method + " | " + r.label + " |";
      for (const auto& g : names) {
        const RegionError* e = region_named(r, g.name);
        line += " " + (e ? num(e->rel_err) + (std::isfinite(e->floor_rel_err) ? " / " + num(e->floor_rel_err) : "")
                         : std::string("–")) + " |";
      }
      f << bold_default(r, line + "\n");
    }
  }
  if (!f) fail(path, ": write failed");
  f.close();
  std::rename((path + ".partial").c_str(), path.c_str());
}

void write_bench_plot_svg(const std::vector<BenchRow>& rows, const std::string& path, const std::string& title) {
  // Log-log axes: x = ms per step, y = relative error (the reference sits at 0
  // error, so it is drawn as a vertical line at its step time).
  const double W = 900, H = 480, L = 80, R = 300, T = 50, B = 60;
  double xmin = 1e9, xmax = 0, ymin = 1e9, ymax = 0;
  for (const auto& r : rows) {
    if (r.method == "floor") continue;
    xmin = std::min(xmin, std::max(r.ms_median, 1e-3));
    xmax = std::max(xmax, r.ms_median);
    if (r.method != "reference") {
      ymin = std::min(ymin, std::max(r.rel_err, 1e-4));
      ymax = std::max(ymax, r.rel_err);
    }
  }
  const double lx0 = std::floor(std::log10(xmin)), lx1 = std::ceil(std::log10(xmax) + 1e-9);
  const double ly0 = std::floor(std::log10(ymin)), ly1 = std::max(std::ceil(std::log10(ymax) + 1e-9), ly0 + 1);
  auto X = [&](double v) { return L + (std::log10(std::max(v, 1e-3)) - lx0) / (lx1 - lx0) * (W - L - R); };
  auto Y = [&](double v) { return H - B - (std::log10(std::max(v, 1e-4)) - ly0) / (ly1 - ly0) * (H - T - B); };
  std::ofstream f(path + ".partial");
  if (!f) fail(path, ": cannot write");
  f << "<svg xmlns='http://www.w3.org/2000/svg' width='" << W << "' height='" << H
    << "' font-family='sans-serif' font-size='12'>\n<rect width='100%' height='100%' fill='white'/>\n";
  f << "<text x='" << W / 2 << "' y='24' text-anchor='middle' font-size='15'>" << title << "</text>\n";
  for (double e = lx0; e <= lx1; ++e)
    f << "<line x1='" << X(std::pow(10, e)) << "' y1='" << T << "' x2='" << X(std::pow(10, e)) << "' y2='" << H - B
      << "' stroke='#ddd'/><text x='" << X(std::pow(10, e)) << "' y='" << H - B + 18 << "' text-anchor='middle'>"
      << std::pow(10, e) << "</text>\n";
  for (double e = ly0; e <= ly1; ++e)
    f << "<line x1='" << L << "' y1='" << Y(std::pow(10, e)) << "' x2='" << W - R << "' y2='" << Y(std::pow(10, e))
      << "' stroke='#ddd'/><text x='" << L - 6 << "' y='" << Y(std::pow(10, e)) + 4 << "' text-anchor='end'>"
      << std::pow(10, e) << "</text>\n";
  f << "<rect x='" << L << "' y='" << T << "' width='" << W - L - R << "' height='" << H - T - B
    << "' fill='none' stroke='black'/>\n";
  f << "<text x='" << (L + W - R) / 2 << "' y='" << H - 18 << "' text-anchor='middle'>ms per step (median, log)</text>\n";
  f << "<text transform='translate(20," << (T + H - B) / 2
    << ") rotate(-90)' text-anchor='middle'>relative soft-displacement error (log)</text>\n";
  int legend = 0;
  for (const auto& r : rows) {
    if (r.method == "floor") continue;  // no simulation: no step time, no simulated error
    std::string label, color;
    char buf[128];
    if (r.method == "reference") {
      std::snprintf(buf, sizeof buf, "full-FEM reference %.0f ms", r.ms_median);
      label = buf;
      color = "#444";
      f << "<line x1='" << X(r.ms_median) << "' y1='" << T << "' x2='" << X(r.ms_median) << "' y2='" << H - B
        << "' stroke='" << color << "' stroke-dasharray='6,4'/>\n";
    } else {
      label = r.label;
      if (r.method == "skinning")
        color = "#d62728";
      else if (r.method == "peer")
        color = "#8c564b";
      else if (r.newton_iters > 1)
        color = "#2ca02c";
      else if (r.dt != rows[0].dt)
        color = "#ff7f0e";
      else if (r.label.find("tets") != std::string::npos || r.label.find("cell") != std::string::npos)
        color = "#9467bd";
      else
        color = "#1f77b4";
      f << "<circle cx='" << X(r.ms_median) << "' cy='" << Y(r.rel_err) << "' r='" << (r.is_default ? 7 : 5)
        << "' fill='" << color << "' stroke='black'/>\n";
    }
    const double ly = T + 14 + 18 * legend++;
    f << "<circle cx='" << W - R + 14 << "' cy='" << ly - 4 << "' r='5' fill='" << color << "'/><text x='" << W - R + 24
      << "' y='" << ly << "'>" << label << "</text>\n";
  }
  f << "</svg>\n";
  f.close();
  std::rename((path + ".partial").c_str(), path.c_str());
}

}  // namespace sflsh
