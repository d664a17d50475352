#include "sflsh/sim/step.hpp"

#include <algorithm>
#include <cmath>

#include <tbb/parallel_for.h>

#include "sflsh/core/error.hpp"
#include "sflsh/core/timer.hpp"
#include "sim/step_workspace.hpp"

namespace sflsh {
namespace {

/// Translates every bone of `bones` by `d` (world): G ← T(d) G.
void translate_bones(std::vector<Isometry>& bones, const Vec3& d) {
  for (Isometry& G : bones) G.translation() += d;
}

void validate_inputs(const Model& m, const StepInputs& in) {
  require(in.bodies.size() == m.bodies().size(), "step: inputs for ", in.bodies.size(), " bodies, the model has ",
          m.bodies().size());
  for (size_t b = 0; b < in.bodies.size(); ++b) {
    const Model::Body& body = m.bodies()[b];
    if (body.rigid()) {
      require(in.bodies[b].bones.empty(), "step: body '", body.name,
              "' is a dynamic rigid object; it takes no target bones, got ", in.bodies[b].bones.size());
    } else {
      require(in.bodies[b].bones.size() == 24, "step: body '", body.name, "' has ", in.bodies[b].bones.size(),
              " target bones, expected 24");
    }
  }
}

/// World point a body's step frame is centred on: its pelvis at time t (a
/// rigid object's centre of mass).
Vec3 pelvis_origin(const Model::Body& b, const Configuration& q) {
  const Isometry& G = q.bones[0];
  return b.avatar && b.avatar->joints_rest.rows() > 0 ? Vec3(G * Vec3(b.avatar->joints_rest.row(0).transpose()))
                                                       : Vec3(G.translation());
}

/// The step's world frames by id, translated by −c into the step frame
/// (frames set by name resolved against the model's names).
void gather_frames(const Model& m, const StepInputs& in, const Vec3& c, GroupWorkspace& ws) {
  const size_t F = m.frame_names().size();
  ws.frames.assign(F, WorldFrame{});
  ws.frame_given.assign(F, 0);
  for (size_t i = 0; i < F; ++i)
    if (const WorldFrame* f = in.frames.find(FrameId{int(i)})) {
      ws.frames[i] = *f;
      ws.frame_given[i] = 1;
    }
  for (const auto& [name, f] : in.frames.by_name())
    if (const FrameId id = m.find_frame(name); id.valid()) {
      ws.frames[size_t(id.index)] = f;
      ws.frame_given[size_t(id.index)] = 1;
    }
  for (WorldFrame& f : ws.frames) f.pose.translation() -= c;
}

/// One group's step (step.hpp): its own frame, its own Newton system.
StepReport step_group(const Model& m, int gi, State& s, const StepInputs& inputs, GroupWorkspace& ws) {
  const Model::Group& g = m.groups()[gi];
  const ModelOptions& o = m.options();
  // Re-centre the world on the group's first pelvis for this step (step.hpp).
  // Inertia predictions shift with q_t, q_{t−1} (x* = 2x_t − x_{t−1} moves by
  // the same −c), targets and frames shift with the bones, and gravity's
  // energy changes by the constant M g·c, which has no gradient.
  const Vec3 c = pelvis_origin(m.bodies()[g.bodies[0]], s.bodies[g.bodies[0]].q);
  ws.targets.resize(g.bodies.size());
  for (size_t k = 0; k < g.bodies.size(); ++k) {
    ws.targets[k] = inputs.bodies[g.bodies[k]];
    translate_bones(ws.targets[k].bones, -c);
    ws.targets[k].pose.translation -= c;
  }
  gather_frames(m, inputs, c, ws);
  for (int b : g.bodies) {
    translate_bones(s.bodies[b].q.bones, -c);
    translate_bones(s.bodies[b].q_prev.bones, -c);
  }

  StepSystem& sys = ws.system;
  sys.size = g.size;
  sys.bodies = g.layouts;
  sys.terms.clear();
  for (size_t k = 0; k < g.terms.size(); ++k) {
    const int i = g.terms[k];
    const Model::BoundTerm& t = m.terms()[i];
    const std::vector<int>& slots = g.slots[k];
    StepContext& ctx = ws.contexts[k];
    const int b0 = t.bodies[0];
    ctx.avatar = m.bodies()[b0].avatar.get();
    ctx.layout = t.local_layouts[0];
    ctx.h = o.h;
    ctx.gravity = o.gravity;
    ctx.q_prev = s.bodies[b0].q;        // q at time t
    ctx.q_prev2 = s.bodies[b0].q_prev;  // q at time t − h
    ctx.target_pose = ws.targets[slots[0]].pose;
    ctx.target_bones = ws.targets[slots[0]].bones;
    ctx.frame_origin = c;
    ctx.frames.clear();
    for (FrameId f : t.frames)
      ctx.frames.push_back(ws.frame_given[size_t(f.index)] ? &ws.frames[size_t(f.index)] : nullptr);
    const size_t set = size_t(t.anchor_set.index);
    ctx.anchors = t.anchor_set.valid() && set < inputs.anchors.size() ? &inputs.anchors[set] : nullptr;
    ctx.bound.clear();
    for (size_t j = 0; j < t.bodies.size(); ++j) {
      const int b = t.bodies[j];
      ctx.bound.push_back({b, slots[j], m.bodies()[b].avatar.get(), t.local_layouts[j], nullptr, &s.bodies[b].q,
                           &s.bodies[b].q_prev});
    }
    ctx.cache = ws.caches[k].get();
    t.term->begin_step(ctx);
    sys.terms.push_back({t.term.get(), &ctx, g.placements[k], t.term->active(ctx)});
  }
  // Start Newton from q_t; kinematic bodies' bones are already final.
  std::vector<Configuration> q;
  q.reserve(g.bodies.size());
  for (size_t k = 0; k < g.bodies.size(); ++k) {
    q.push_back(s.bodies[g.bodies[k]].q);
    if (!m.bodies()[g.bodies[k]].bones_dynamic) q.back().bones = ws.targets[k].bones;
  }
  StepReport rep = newton_minimize(sys, q, o.newton);
  for (size_t k = 0; k < sys.terms.size(); ++k) {
    const SystemTerm& t = sys.terms[k];
    if (!t.active) continue;
    for (BoundBody& bb : t.ctx->bound) bb.q = &q[bb.slot];
    const int b0 = t.ctx->bound[0].body;
    for (TermQuantity& v : t.term->report(*t.ctx, q[t.ctx->bound[0].slot])) {
      // A point a term reports is in this step's centred frame: back to the world.
      if (v.name == "contact_point" && v.value.size() == 3) v.value += c;
      rep.quantities.push_back({t.term->name(), b0, v.name, v.unit,
                                std::vector<double>(v.value.data(), v.value.data() + v.value.size()), g.terms[k]});
    }
  }
  for (size_t k = 0; k < g.bodies.size(); ++k) {
    const int b = g.bodies[k];
    BodyState& st = s.bodies[b];
    translate_bones(st.q.bones, c);
    st.q_prev = std::move(st.q);
    translate_bones(q[k].bones, c);
    // Kinematic: the prescribed bones exactly, not shifted there and back.
    if (!m.bodies()[b].bones_dynamic) q[k].bones = inputs.bodies[b].bones;
    st.q = std::move(q[k]);
  }
  // The contexts point into this step's locals: drop the pointers.
  for (StepContext& ctx : ws.contexts) {
    ctx.frames.clear();
    ctx.anchors = nullptr;
    ctx.bound.clear();
  }
  return rep;
}

/// Adds group report `g` into `total` (terms in model order: `term_index` maps g's).
void merge_report(StepReport& total, StepReport& g, const std::vector<int>& term_index) {
  for (size_t k = 0; k < g.energies.size(); ++k) total.energies[term_index[k]] = std::move(g.energies[k]);
  for (TermQuantityReport& v : g.quantities) total.quantities.push_back(std::move(v));
  total.energy_before += g.energy_before;
  total.energy_after += g.energy_after;
  total.grad_norm_before = std::hypot(total.grad_norm_before, g.grad_norm_before);
  total.grad_norm_after = std::hypot(total.grad_norm_after, g.grad_norm_after);
  total.newton_decrement = std::hypot(total.newton_decrement, g.newton_decrement);
  total.step_scale = std::min(total.step_scale, g.step_scale);
  total.regularization = std::max(total.regularization, g.regularization);
  total.iterations = std::max(total.iterations, g.iterations);
  total.iterations_after_damping = std::max(total.iterations_after_damping, g.iterations_after_damping);
  total.iterations_for_nonlinearity = std::max(total.iterations_for_nonlinearity, g.iterations_for_nonlinearity);
  total.accepted += g.accepted;
  total.damped += g.damped;
  total.rejected += g.rejected;
  if (int(g.outcome) > int(total.outcome)) total.outcome = g.outcome;
  total.ms_assemble += g.ms_assemble;
  total.ms_solve += g.ms_solve;
}

}  // namespace

Vec3 step_frame_origin(const Model& m, const State& s) {
  if (m.bodies().empty()) return Vec3::Zero();
  return pelvis_origin(m.bodies()[0], s.bodies[0].q);
}

StepReport step(const Model& m, State& s, const StepInputs& inputs) {
  validate_inputs(m, inputs);
  require(s.bodies.size() == m.bodies().size(), "step: state has ", s.bodies.size(), " bodies, the model has ",
          m.bodies().size());
  StepWorkspace& ws = s.workspace(m);
  const int G = int(m.groups().size());
  StepReport rep;
  if (G == 1) {
    rep = step_group(m, 0, s, inputs, ws.groups[0]);
  } else {
    Timer wall;
    std::vector<StepReport> reports(G);
    auto run = [&](int g) { reports[g] = step_group(m, g, s, inputs, ws.groups[g]); };
    if (m.options().parallel_groups) {
      tbb::parallel_for(0, G, run);
    } else {
      for (int g = 0; g < G; ++g) run(g);
    }
    rep.energies.resize(m.terms().size());
    rep.step_scale = 1;
    for (int g = 0; g < G; ++g) merge_report(rep, reports[g], m.groups()[g].terms);
    rep.ms_total = wall.ms();  // wall time: groups may have run concurrently
  }
  s.time += m.options().h;
  rep.time = s.time;
  return rep;
}

}  // namespace sflsh
