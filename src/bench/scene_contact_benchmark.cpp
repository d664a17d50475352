#include "sflsh/bench/scene_contact_benchmark.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "bench/step_median.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/core/progress.hpp"
#include "sflsh/core/timer.hpp"
#include "sflsh/geometry/primitive_sdfs.hpp"
#include "sflsh/reference/full_fem.hpp"
#include "sflsh/reference/scene_reference_run.hpp"
#include "sflsh/scene/rigid_object.hpp"
#include "sflsh/scene/scene_run.hpp"
#include "sflsh/scene/scene_session.hpp"

namespace sflsh {
namespace {

const double kNaN = std::numeric_limits<double>::quiet_NaN();

const std::string& scene_name(const SceneDescription& sc) {
  static const std::string unnamed = "scene";
  return sc.path.empty() ? unnamed : sc.path;
}

/// An object or tool with a shape that touches the body: what the reference
/// makes an obstacle of, in its order (objects, then tools); then the tools
/// without a shape that grasp (compared by the force on the tool, their
/// "dent" the skin's largest |u| within reach of a sensor's end: the lifted skin).
struct Partner {
  std::string name;
  geometry::SdfPtr field;  // shape frame (a grasping tool: a ball over its sensors' reach at its origin)
  bool kinematic = false;
  int grasp_tool = -1;     // a grasping tool: its index in the scene's tools
};

/// Whether the body and `name` collide as the reference takes it: every pair,
/// or the pair listed in contact.pairs (tools included).
bool collides(const ContactDescription& c, const std::string& body, const std::string& name) {
  if (c.all_pairs) return true;
  for (const auto& [a, b] : c.pairs)
    if ((a == body && b == name) || (a == name && b == body)) return true;
  return false;
}

std::vector<Partner> contact_partners(const SceneDescription& sc) {
  std::vector<Partner> out;
  const std::string& body = sc.bodies.at(0).name;
  for (const RigidObjectDescription& o : sc.objects)
    if (collides(sc.contact, body, o.name))
      out.push_back({o.name, make_rigid_object(o).field, o.kind == ObjectKind::Kinematic});
  for (const ToolDescription& t : sc.tools) {
    if (!t.has_shape || !collides(sc.contact, body, t.name)) continue;
    RigidObjectDescription d;
    d.name = t.name;
    d.shape = t.shape;
    d.kind = ObjectKind::Kinematic;
    out.push_back({t.name, make_rigid_object(d).field, true});
  }
  for (size_t i = 0; i < sc.tools.size(); ++i) {
    const ToolDescription& t = sc.tools[i];
    if (t.has_shape || t.sensors.empty()) continue;
    double reach = 0;
    for (const ToolSensorDescription& s : t.sensors) reach = std::max(reach, s.origin.norm() + s.range);
    out.push_back({t.name, std::make_shared<geometry::SphereSdf>(reach), true, int(i)});
  }
  return out;
}

/// The largest |u| (m) of the skin vertices whose world position x lies
/// within `reach` of the surface of `field` placed at `pose`.
double near_dent(const Points& x, const Points& u, const geometry::Sdf& field, const Isometry& pose, double reach) {
  const Isometry to_shape = pose.inverse();
  double dent = 0;
  for (int v = 0; v < int(x.rows()); ++v)
    if (field.distance(to_shape * Vec3(x.row(v).transpose())) < reach) dent = std::max(dent, u.row(v).norm());
  return dent;
}

/// Step times between successive calls of lap() (ms, wall or thread CPU).
class StepClock {
 public:
  explicit StepClock(bool cpu) : cpu_(cpu) { start(); }
  void start() { last_ = now(); }
  /// The time since start() or the previous lap's end(); call end() when the caller's own work is done.
  double lap() const { return now() - last_; }
  void end() { last_ = now(); }

 private:
  double now() const { return cpu_ ? thread_cpu_ms() : wall_.ms(); }
  bool cpu_;
  Timer wall_;
  double last_ = 0;
};

/// The scene with its output frames reduced to the first (the runs keep
/// none; frames would only add to the step times).
SceneDescription without_frames(const SceneDescription& sc) {
  SceneDescription out = sc;
  out.output.fps = 1e-9;
  return out;
}

/// The scene with `partners` removed (objects, tools and the pairs naming them).
SceneDescription without_partners(const SceneDescription& sc, const std::vector<Partner>& partners) {
  auto listed = [&](const std::string& name) {
    for (const Partner& p : partners)
      if (p.name == name) return true;
    return false;
  };
  SceneDescription out = sc;
  out.objects.clear();
  for (const RigidObjectDescription& o : sc.objects)
    if (!listed(o.name)) out.objects.push_back(o);
  out.tools.clear();
  for (const ToolDescription& t : sc.tools)
    if (!listed(t.name)) out.tools.push_back(t);
  out.contact.pairs.clear();
  for (const auto& pr : sc.contact.pairs)
    if (!listed(pr.first) && !listed(pr.second)) out.contact.pairs.push_back(pr);
  return out;
}

/// Peak, errors, dents, depth and patch of a pair whose per-step series are filled.
void summarize(SceneContactPair& p, double threshold) {
  p.peak_full_n = p.peak_reduced_n = 0;
  for (size_t i = 0; i < p.force_full_n.size(); ++i) {
    p.peak_full_n = std::max(p.peak_full_n, p.force_full_n[i]);
    p.peak_reduced_n = std::max(p.peak_reduced_n, p.force_reduced_n[i]);
    p.dent_full_max_mm = std::max(p.dent_full_max_mm, p.dent_full_mm[i]);
    p.dent_reduced_max_mm = std::max(p.dent_reduced_max_mm, p.dent_reduced_mm[i]);
    p.max_patch_nodes = std::max(p.max_patch_nodes, p.patch_nodes[i]);
    p.contact_steps_full += p.force_full_n[i] > 0;
    p.contact_steps_reduced += p.force_reduced_n[i] > 0;
  }
  p.peak_err = p.peak_full_n > 0 ? std::abs(p.peak_reduced_n - p.peak_full_n) / p.peak_full_n : kNaN;
  double sum = 0;
  p.rms_steps = 0;
  for (size_t i = 0; i < p.force_full_n.size(); ++i) {
    const double f = p.force_full_n[i];
    if (!(f > 0) || f <= threshold * p.peak_full_n) continue;
    sum += std::pow((p.force_reduced_n[i] - f) / f, 2);
    ++p.rms_steps;
  }
  p.rms_err = p.rms_steps > 0 ? std::sqrt(sum / p.rms_steps) : kNaN;
  p.max_depth_mm = kNaN;
  for (double d : p.depth_mm)
    if (std::isfinite(d)) p.max_depth_mm = std::isfinite(p.max_depth_mm) ? std::max(p.max_depth_mm, d) : d;
}

/// The full-FEM reference's run of the scene: per step its time, whether any
/// partner touches, and per partner the force and position (the forces and
/// dents also into res.pairs, the times into res.time).
struct ReferenceTrace {
  std::vector<double> ms;
  std::vector<bool> contact;
  std::vector<std::vector<Vec3>> force, position;
};

ReferenceTrace run_reference(const SceneDescription& sc, const std::vector<Partner>& partners,
                             const SceneContactBenchSettings& set, SceneContactBenchResult& res) {
  const std::string& where = res.scene;
  const size_t np = partners.size();
  size_t n_obstacles = 0;  // the partners with a shape come first (contact_partners)
  for (const Partner& p : partners) n_obstacles += p.grasp_tool < 0;
  ReferenceTrace t;
  t.force.resize(np);
  t.position.resize(np);
  SceneReferenceOptions ro;
  ro.progress = set.progress;
  ro.on_step = [&](const SceneReferenceStep& s) {
    const FullFemReport& rep = *s.report;
    require(rep.contacts.size() == n_obstacles, where, ": the full-FEM reference has ", rep.contacts.size(),
            " obstacles, expected ", n_obstacles);
    require(s.fem->displacement().allFinite(), where, ": the full-FEM reference became non-finite at step ", s.step,
            " (t = ", s.time, " s)");
    const Points x = s.fem->posed_surface(), u = s.fem->soft_displacement();
    bool any = false;
    for (size_t i = 0; i < np; ++i) {
      const int tool = partners[i].grasp_tool;
      const Vec3 f = tool < 0 ? rep.contacts[i].force : s.tool_forces->at(size_t(tool));
      const Isometry& pose = tool < 0 ? s.obstacle_poses->at(i) : s.tool_poses->at(size_t(tool));
      require(f.allFinite(), where, ": the full-FEM ", tool < 0 ? "contact" : "grasp", " force of '", partners[i].name,
              "' became non-finite at step ", s.step, " (t = ", s.time, " s)");
      t.force[i].push_back(f);
      t.position[i].push_back(pose.translation());
      res.pairs[i].force_full_n.push_back(f.norm());
      res.pairs[i].dent_full_mm.push_back(1e3 * near_dent(x, u, *partners[i].field, pose, set.dent_reach));
      any = any || f.norm() > 0;
    }
    res.time.push_back(s.time);
    t.ms.push_back(set.cpu_time ? s.cpu_ms : rep.ms_total);
    t.contact.push_back(any);
  };
  log_info("bench-contact: " + where + ": full-FEM reference");
  run_scene_reference(sc, ro);
  return t;
}

/// The reduced solver's run of the scene as `sflsh simulate` runs it: per
/// step its time and whether any partner touches (the forces, dents and patch
/// sizes into res.pairs).
struct ReducedTrace {
  std::vector<double> ms;
  std::vector<bool> contact;
};

ReducedTrace run_reduced(const SceneDescription& sc, const std::vector<Partner>& partners,
                         const SceneContactBenchSettings& set, SceneContactBenchResult& res) {
  const std::string& where = res.scene;
  const size_t np = partners.size();
  ReducedTrace t;
  std::vector<double>& ms_with = t.ms;
  std::vector<bool>& contact_with = t.contact;
  SceneSessionOptions so;
  so.progress = set.progress;
  so.inject_nan_at_step = set.inject_nan_at_step;
  SceneSession session(sc, so);
  const SimulationResult header = session.result_header();
  std::vector<int> object_index(np, -1);
  for (size_t i = 0; i < np; ++i)
    for (size_t j = 0; j < header.objects.size(); ++j)
      if (header.objects[j].name == partners[i].name) object_index[i] = int(j);
  const int body = session.body_model_index(0);
  for (const Partner& p : partners)
    require(p.grasp_tool < 0 || session.tool_index(p.name) == p.grasp_tool, where, ": tools '", p.name,
            "' is not the scene's tool ", p.grasp_tool);
  SceneRunOptions ro;
  ro.progress = set.progress;
  ro.keep_frames = false;
  StepClock clock(set.cpu_time);
  ro.on_step = [&](const Simulator&, const StepReport& rep) {
    ms_with.push_back(clock.lap());
    const FrameData fr = session.frame(0.0);  // skin with the patches' dents; one body: its rows
    const std::vector<Isometry> poses = session.object_poses();
    bool any = false;
    for (size_t i = 0; i < np; ++i) {
      const std::string term = "contact:" + partners[i].name;
      double force = 0;
      int nodes = 0;
      const int tool = partners[i].grasp_tool;
      for (const TermQuantityReport& q : rep.quantities) {
        if (q.body != body) continue;
        if (tool >= 0) {  // a grasping tool's patch: its anchor terms'
          const std::vector<int>& at = session.compiled_tool(tool).anchor_terms;
          if (q.name == "patch_nodes" && q.value.size() == 1 && std::count(at.begin(), at.end(), q.term_index))
            nodes = std::max(nodes, int(q.value[0]));
          continue;
        }
        if (q.term != term) continue;
        if (q.name == "force" && q.value.size() == 3) force = Vec3(q.value[0], q.value[1], q.value[2]).norm();
        if (q.name == "patch_nodes" && q.value.size() == 1) nodes = int(q.value[0]);
      }
      if (tool >= 0) force = session.tool_state(tool).force.norm();  // on the tool: its anchors
      require(std::isfinite(force), where, ": the reduced ", tool < 0 ? "contact" : "grasp", " force of '",
              partners[i].name, "' became non-finite at step ", ms_with.size());
      SceneContactPair& p = res.pairs[i];
      p.force_reduced_n.push_back(force);
      p.patch_nodes.push_back(nodes);
      const bool placed = tool >= 0 || object_index[i] >= 0;
      const Isometry pose = tool >= 0 ? session.tool_state(tool).pose
                                      : object_index[i] >= 0 ? poses.at(size_t(object_index[i])) : Isometry::Identity();
      p.dent_reduced_mm.push_back(
          placed ? 1e3 * near_dent(fr.positions, fr.displacement, *partners[i].field, pose, set.dent_reach) : 0.0);
      any = any || force > 0;
    }
    contact_with.push_back(any);
    clock.end();
  };
  log_info("bench-contact: " + where + ": reduced solver");
  clock.start();
  try {
    run_scene(session, ro);
  } catch (const SimulationStopped& e) {
    fail("reduced solver: ", e.what());
  }
  return t;
}

/// The step times of the scene without the compared objects and tools.
std::vector<double> step_times_without(const SceneDescription& sc, const std::vector<Partner>& partners,
                                       const SceneContactBenchSettings& set, const SceneContactBenchResult& res) {
  std::vector<double> ms_without;
  SceneSessionOptions so;
  so.progress = set.progress;
  SceneSession session(without_partners(sc, partners), so);
  SceneRunOptions ro;
  ro.progress = set.progress;
  ro.keep_frames = false;
  StepClock clock(set.cpu_time);
  ro.on_step = [&](const Simulator&, const StepReport&) {
    ms_without.push_back(clock.lap());
    clock.end();
  };
  log_info("bench-contact: " + res.scene + ": reduced solver without " + res.removed);
  clock.start();
  run_scene(session, ro);
  return ms_without;
}

}  // namespace

void check_scene_contact_bench(const SceneDescription& sc) {
  check_scene_reference(sc);
  require(!contact_partners(sc).empty(), scene_name(sc), ": body '", sc.bodies.at(0).name,
          "' touches no object and no tool with a shape (contact.pairs) and no tool grasps; bench-contact compares "
          "contact and grasp forces");
}

SceneContactBenchResult run_scene_contact_bench(const SceneDescription& scene, const SceneContactBenchSettings& set) {
  check_scene_contact_bench(scene);
  require(std::isfinite(set.force_threshold) && set.force_threshold >= 0 && set.force_threshold < 1 &&
              std::isfinite(set.dent_reach) && set.dent_reach > 0,
          "bench-contact: force threshold in [0, 1) and a positive dent reach expected, got ", set.force_threshold,
          " and ", set.dent_reach);
  const std::string& where = scene_name(scene);
  const std::vector<Partner> partners = contact_partners(scene);
  const SceneDescription sc = without_frames(scene);
  SceneContactBenchResult res;
  res.scene = where;
  res.body = sc.bodies[0].name;
  res.dt = sc.solver.dt;
  res.patch = sc.contact.patch;
  for (const Partner& p : partners) {
    SceneContactPair pair;
    pair.object = p.name;
    pair.kinematic = p.kinematic;
    res.pairs.push_back(std::move(pair));
    res.removed += (res.removed.empty() ? "" : ", ") + p.name;
  }
  const size_t np = partners.size();
  const ReferenceTrace full = run_reference(sc, partners, set, res);
  const std::vector<double>& ms_full = full.ms;
  const std::vector<bool>& contact_full = full.contact;
  const std::vector<std::vector<Vec3>>&force_full = full.force, &position = full.position;

  bool touched = false;
  for (bool c : contact_full) touched = touched || c;
  require(touched, where, ": the full-FEM reference has no contact between body '", res.body, "' and ", res.removed,
          " in ", contact_full.size(), " steps; nothing to compare");

  const ReducedTrace reduced = run_reduced(sc, partners, set, res);
  const std::vector<double>& ms_with = reduced.ms;
  const std::vector<bool>& contact_with = reduced.contact;
  const std::vector<double> ms_without = step_times_without(sc, partners, set, res);
  require(ms_with.size() == contact_full.size() && ms_without.size() == ms_with.size(), where,
          ": the runs took different step counts (full FEM ", contact_full.size(), ", reduced ", ms_with.size(),
          ", without contact ", ms_without.size(), ")");

  // Depth: a kinematic partner's travel since the full FEM's first contact step, along its peak force.
  const bool still_body = sc.bodies[0].motion == "none";
  for (size_t i = 0; i < np; ++i) {
    SceneContactPair& p = res.pairs[i];
    const std::vector<double>& f = p.force_full_n;
    const auto first = std::find_if(f.begin(), f.end(), [](double v) { return v > 0; });
    if (!still_body || !p.kinematic || first == f.end()) {
      p.depth_mm.assign(f.size(), kNaN);
    } else {
      const size_t s0 = size_t(first - f.begin());
      const size_t peak = size_t(std::max_element(f.begin(), f.end()) - f.begin());
      const Vec3 n = force_full[i][peak].normalized();
      for (size_t k = 0; k < f.size(); ++k) p.depth_mm.push_back(1e3 * (position[i][k] - position[i][s0]).dot(n));
    }
    summarize(p, set.force_threshold);
  }
  for (bool c : contact_with) res.contact_steps += c;
  res.ms_contact = median_when(ms_with, contact_with);
  res.ms_no_contact = median_when(ms_without, contact_with);
  res.step_ratio = res.ms_contact / res.ms_no_contact;
  res.ms_full = median_when(ms_full, contact_full);
  return res;
}

}  // namespace sflsh
