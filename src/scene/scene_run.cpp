#include "sflsh/scene/scene_run.hpp"

#include <fstream>
#include <iomanip>
#include <map>
#include <set>
#include <sstream>

#include "sflsh/core/error.hpp"
#include "sflsh/core/interrupt.hpp"
#include "sflsh/core/progress.hpp"
#include "sflsh/io/atomic_output.hpp"
#include "sflsh/scene/scene_session.hpp"
#include "sflsh/sim/finite_guard.hpp"
#include "sflsh/sim/momentum.hpp"

namespace sflsh {

void SceneContactStats::write_tool_log(const std::string& path) const {
  io::AtomicOutput out(path);
  {
    std::ofstream o(out.temp_path());
    require(bool(o), path, ": cannot write the tool log");
    o << "time,tool,fx,fy,fz,anchors,max_stretch\n" << std::setprecision(9);
    for (const ToolStep& s : tool_steps)
      o << s.time << "," << s.tool << "," << s.force.x() << "," << s.force.y() << "," << s.force.z() << ","
        << s.anchors << "," << s.max_stretch << "\n";
    require(bool(o), path, ": writing the tool log failed");
  }
  out.commit();
}

std::string SceneContactStats::describe() const {
  std::ostringstream o;
  o << std::fixed;
  for (const ToolEvent& e : tool_events)
    o << "tool " << e.tool << " t = " << std::setprecision(3) << e.time << " s: " << e.kind << " " << e.points
      << " skin points of " << e.body << "\n";
  if (!tool_steps.empty()) {
    double fmax = 0, stretch = 0;
    for (const ToolStep& s : tool_steps) {
      fmax = std::max(fmax, s.force.norm());
      stretch = std::max(stretch, s.max_stretch);
    }
    o << "tools: peak force " << std::setprecision(2) << fmax << " N, largest anchor stretch "
      << stretch * 1e3 << " mm\n";
  }
  for (const Pair& p : pairs)
    o << "contact " << p.term << " on " << p.body << ": max penetration " << std::setprecision(2)
      << p.max_penetration * 1e3 << " mm, max force " << std::setprecision(1) << p.max_force << " N, in contact "
      << p.active_steps << " steps; at the end " << p.last_force.transpose() << " N\n";
  const double p0 = momentum_start.norm();
  o << std::setprecision(4) << "linear momentum: start " << p0 << " kg m/s, end " << momentum_end.norm()
    << " kg m/s (change " << std::scientific << std::setprecision(2) << (momentum_end - momentum_start).norm()
    << ")\n";
  return o.str();
}

SimulationResult run_scene(const SceneDescription& sc, const SceneRunOptions& opt, SceneContactStats* stats) {
  SceneSessionOptions so;
  so.progress = opt.progress;
  so.body_push_limit = opt.body_push_limit;
  SceneSession session(sc, so);
  const Simulator& sim = session.simulator();
  const long steps = session.total_steps();
  SimulationResult r = session.result_header();
  session.record_frame(r, 0.0);

  SceneContactStats st;
  st.momentum_start = linear_momentum(sim.model(), sim.scene_state());
  std::map<std::pair<std::string, int>, size_t> pair_index;
  // Tools' anchors and couplings: reported in tool_steps, not as contact pairs.
  std::set<int> tool_terms;
  for (int i = 0; i < session.num_tools(); ++i) {
    const CompiledTool& t = session.compiled_tool(i);
    tool_terms.insert(t.anchor_terms.begin(), t.anchor_terms.end());
    if (t.coupling_term >= 0) tool_terms.insert(t.coupling_term);
  }
  const double frame_dt = 1.0 / sc.output.fps;
  double next_frame = frame_dt, ms_since_frame = 0;
  int steps_since_frame = 0;
  Progress progress("simulating " + r.motion, steps);
  for (long k = 0; k < steps; ++k) {
    if (interrupt_signal()) throw_if_interrupted("at step " + std::to_string(k + 1) + " of " + std::to_string(steps));
    const StepReport* step_report = nullptr;
    try {
      step_report = &session.advance();
    } catch (const NonFiniteError& e) {
      // Keep the frames made so far, marked incomplete (no frame of this step).
      r.incomplete = true;
      r.stop_reason = e.what();
      throw SimulationStopped(e.what(), std::move(r));
    }
    const StepReport& rep = *step_report;
    const double t = (k + 1) * session.dt();
    for (int i = 0; i < session.num_tools(); ++i) {
      const SceneToolState& ts = session.tool_state(i);
      st.tool_steps.push_back({t, session.tool_name(i), ts.force, ts.anchors, ts.max_stretch});
    }
    // Contact figures from the terms' reports.
    for (SceneContactStats::Pair& p : st.pairs) p.last_force.setZero();  // inactive terms report nothing
    for (const TermQuantityReport& q : rep.quantities) {
      if (tool_terms.count(q.term_index)) continue;
      const auto key = std::make_pair(q.term, q.body);
      auto [it, fresh] = pair_index.try_emplace(key, st.pairs.size());
      if (fresh) st.pairs.push_back({q.term, sim.model().bodies()[q.body].name});
      SceneContactStats::Pair& p = st.pairs[it->second];
      if (q.name == "max_penetration" || q.name == "max_overlap") {
        p.max_penetration = std::max(p.max_penetration, q.value[0]);
        if (q.value[0] > 0) ++p.active_steps;
      } else if (q.name == "force" && q.value.size() == 3) {
        p.last_force = Vec3(q.value[0], q.value[1], q.value[2]);
        p.max_force = std::max(p.max_force, p.last_force.norm());
      }
    }
    r.add_step(t, rep);
    ms_since_frame += rep.ms_total;
    ++steps_since_frame;
    if (t + 1e-9 >= next_frame) {
      session.record_frame(r, ms_since_frame / steps_since_frame);
      next_frame += frame_dt;
      ms_since_frame = 0;
      steps_since_frame = 0;
    }
    if (opt.progress) progress.update(k + 1);
  }
  if (opt.progress) progress.finish();
  st.tool_events = session.tool_events();
  r.tool_events = session.tool_events();  // also those after the last frame
  st.momentum_end = linear_momentum(sim.model(), sim.scene_state());
  if (stats) *stats = std::move(st);
  return r;
}

}  // namespace sflsh
