#pragma once
// Terms bound to two bodies (contact between bodies, a body and a rigid
// object): small box avatars, configurations near rest, a step context
// binding the bodies with their local layouts, and the term's derivatives
// against central differences over the whole local system. Header-only, for
// tests/sim/*_test.cpp.
#include <algorithm>
#include <map>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "sflsh/sim/energy_term.hpp"
#include "sim/skeleton_fixture.hpp"
#include "sim/synthetic_avatar.hpp"

namespace sflsh::test::two_body {

inline constexpr double kH = 1.0 / 60.0;

inline Avatar box(int handles = 6, int cells = 2, double cell = 0.04) {
  test::SyntheticAvatarOptions o;
  o.nx = o.nz = cells;
  o.cell = cell;
  o.handles = handles;
  o.handle_radius = 0.1;
  o.all_tets = false;
  o.samples = 10;
  Avatar a = test::make_synthetic_avatar(o);  // default: box x, z ∈ [−0.04, 0.04], y ∈ [0, 0.12]
  a.joints_rest = test::make_tpose_skeleton().joints_rest;
  a.capsules = {{3, Vec3(0, 0.03, 0), Vec3(0, 0.09, 0), 0.03}};
  return a;
}

inline Isometry small_motion(std::mt19937& rng, double angle, double shift) {
  std::normal_distribution<double> n;
  Isometry G = Isometry::Identity();
  G.linear() = Eigen::AngleAxisd(angle * n(rng), Vec3(n(rng), n(rng), n(rng)).normalized()).toRotationMatrix();
  G.translation() = shift * Vec3(n(rng), n(rng), n(rng));
  return G;
}

/// A configuration near rest: bones moved slightly, z random (m).
inline Configuration near_rest(const Avatar& a, std::mt19937& rng, const Isometry& base = Isometry::Identity()) {
  Configuration q;
  for (int j = 0; j < 24; ++j) q.bones.push_back(base * small_motion(rng, 0.03, 0.003));
  std::uniform_real_distribution<double> u(-0.004, 0.004);
  q.z = VecX(a.num_reduced());
  for (int i = 0; i < q.z.size(); ++i) q.z[i] = u(rng);
  return q;
}

inline DofLayout body_layout(const Avatar& a, bool bones_dynamic, int base = 0) {
  DofLayout l;
  l.bones_dynamic = bones_dynamic;
  l.num_reduced = a.num_reduced();
  l.bone_pivots = a.joints_rest;
  l.base = base;
  return l;
}

inline DofLayout rigid_layout(int base) {
  DofLayout l;
  l.num_bones = 1;
  l.bones_dynamic = true;
  l.num_reduced = 0;
  l.bone_pivots = Points::Zero(1, 3);
  l.base = base;
  return l;
}

/// A context binding the given bodies (configurations at t and t − h) with their local layouts.
struct Bound {
  const Avatar* avatar;
  DofLayout layout;
  Configuration q, q_prev, q_prev2;
};
inline StepContext bind_bodies(std::vector<Bound>& bodies, const std::map<std::string, WorldFrame>* frames) {
  StepContext ctx;
  ctx.avatar = bodies[0].avatar;
  ctx.layout = bodies[0].layout;
  ctx.h = kH;
  ctx.q_prev = bodies[0].q_prev;
  ctx.q_prev2 = bodies[0].q_prev2;
  // The term's one input frame: the only one these tests give.
  if (frames)
    for (const auto& [name, f] : *frames) ctx.frames.push_back(&f);
  for (size_t i = 0; i < bodies.size(); ++i)
    ctx.bound.push_back({int(i), int(i), bodies[i].avatar, bodies[i].layout, &bodies[i].q, &bodies[i].q_prev,
                         &bodies[i].q_prev2});
  return ctx;
}

inline int total_size(const std::vector<Bound>& bodies) {
  int n = 0;
  for (const Bound& b : bodies) n += b.layout.size();
  return n;
}

/// E at the bodies retracted by the global local-system step δ.
inline double energy_at(const EnergyTerm& term, StepContext ctx, std::vector<Bound> bodies, const VecX& delta) {
  std::vector<Configuration> q;
  for (const Bound& b : bodies) q.push_back(retract(b.q, delta, b.layout));
  for (size_t i = 0; i < bodies.size(); ++i) ctx.bound[i].q = &q[i];
  return term.evaluate(ctx, q[0], nullptr, nullptr);
}

struct Derivatives {
  double E;
  VecX grad;
  MatX hess;
};
inline Derivatives analytic(const EnergyTerm& term, const StepContext& ctx, const std::vector<Bound>& bodies) {
  const int n = total_size(bodies);
  Derivatives d{0, VecX::Zero(n), MatX::Zero(n, n)};
  d.E = term.evaluate(ctx, bodies[0].q, &d.grad, &d.hess);
  return d;
}

inline VecX fd_gradient(const EnergyTerm& term, const StepContext& ctx, const std::vector<Bound>& bodies, double eps) {
  const int n = total_size(bodies);
  VecX g(n);
  for (int i = 0; i < n; ++i) {
    VecX d = VecX::Zero(n);
    d[i] = eps;
    g[i] = (energy_at(term, ctx, bodies, d) - energy_at(term, ctx, bodies, -d)) / (2 * eps);
  }
  return g;
}

/// The gradient's translation parts (a force, first) and rotation parts (a
/// torque about the origin, second) summed over every bone of every body:
/// both vanish when the term's forces are internal (equal and opposite, collinear).
inline std::pair<Vec3, Vec3> summed_bone_gradient(const VecX& grad, const std::vector<Bound>& bodies) {
  Vec3 force = Vec3::Zero(), torque = Vec3::Zero();
  for (const Bound& bd : bodies)
    for (int i = 0; i < 24; ++i) {
      torque += grad.segment<3>(bd.layout.bone_offset(i));
      force += grad.segment<3>(bd.layout.bone_offset(i) + 3);
    }
  return {force, torque};
}

inline double rel(const VecX& a, const VecX& b) { return (a - b).norm() / std::max(1e-12, b.norm()); }

}  // namespace sflsh::test::two_body
