// The benchmark's runs along a motion: the full-FEM reference, the reduced
// simulator, skinning alone and the Bullet peer, each recorded as a Trace.
#include "bench/benchmark_internal.hpp"
#include "sflsh/core/timer.hpp"

namespace sflsh::bench_internal {

namespace {

constexpr double kFrameRate = 30.0;  // comparison frames per simulated second

/// Steps per comparison frame for time step h (h must divide 1/30 s).
int steps_per_frame(double h) {
  const double r = 1.0 / (kFrameRate * h);
  const int n = int(std::lround(r));
  require(n >= 1 && std::abs(r - n) < 1e-6, "bench: time step ", h, " s does not divide 1/", kFrameRate, " s");
  return n;
}

}  // namespace

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

namespace {

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

}  // namespace

Trace run_reduced(std::shared_ptr<const Avatar> avatar, const MotionClip& motion, double seconds, double h,
                  int newton_iters, const std::string& label, bool bones_dynamic, bool mean_dilatation,
                  std::optional<double> nonlinearity_tolerance, LinearSolver linear_solver, bool cpu_time) {
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

}  // namespace sflsh::bench_internal
