// The patch term's broad phase (contact_patch.hpp, "Life of a patch"): the
// skin vertices near the object at time t, the candidate faces around them,
// and their samples' friction at t ("Friction").
#include <algorithm>
#include <cmath>
#include <numeric>

#include <Eigen/Geometry>

#include "sflsh/core/error.hpp"
#include "sim/energies/contact_patch_cache.hpp"

namespace sflsh {

using contact_patch_detail::PatchCache;
using contact_patch_detail::patched_vertex;

/// The skin vertices near the object at time t (by increasing index) and
/// their φ; also places the field at t + h (cache's field_pose).
void ContactPatchTerm::find_near_vertices(const StepContext& ctx, TermCache& cache, std::vector<int>& near,
                                          std::vector<double>& near_phi) const {
  PatchCache& c = static_cast<PatchCache&>(cache);
  const geometry::Aabb local = field_->bounds();
  const bool bounded = !local.is_unbounded();
  const double extent = bounded ? 0.5 * (local.max - local.min).norm() : 1.0;
  double object_motion = 0;
  if (dynamic_) {
    // The object's pose at t (the broad phase's reference) and its motion over the last step, doubled.
    require(ctx.bound.size() == 2 && ctx.bound[1].q_prev != nullptr, name(),
            ": a dynamic object's contact is bound to the body and the object");
    const Isometry& G = ctx.bound[1].q_prev->bones[0];
    // A shape that moves on its body (a gripper's jaw): its pose for this step.
    c.shape_in_frame = step_shape_in_frame(ctx.frame(), G, shape_in_frame_, name(), object_);
    c.field_pose = G * c.shape_in_frame;
    if (ctx.bound[1].q_prev2 && !ctx.bound[1].q_prev2->bones.empty()) {
      const Isometry& Gp = ctx.bound[1].q_prev2->bones[0];
      const double angle = Eigen::AngleAxisd(G.linear() * Gp.linear().transpose()).angle();
      object_motion = 2 * ((G.translation() - Gp.translation()).norm() + angle * extent);
    }
  } else {
    require(ctx.frame() != nullptr, name(), ": the step inputs have no world frame '", object_, "'");
    const WorldFrame& f = *ctx.frame();
    require(f.pose.matrix().allFinite(), name(), ": world frame '", object_, "' is not finite");
    c.field_pose = f.pose * shape_in_frame_;
    object_motion = ctx.h * (f.linear_velocity.norm() + f.angular_velocity.norm() * extent);
  }
  const Isometry T_inv = c.field_pose.inverse();
  const geometry::Aabb box = bounded ? local.transformed(c.field_pose) : local;

  // Skin vertices near the object at time t.
  const BoundBody& b = ctx.bound.empty() ? BoundBody{0, 0, ctx.avatar, ctx.layout, nullptr, &ctx.q_prev, &ctx.q_prev2}
                                         : ctx.bound[0];
  const Configuration& qt = *b.q_prev;
  const bool has_prev = b.q_prev2 && b.q_prev2->bones.size() == qt.bones.size();
  for (const VertexCluster& cl : clusters_) {
    // A cluster whose centre, carried by its bone, is farther from the object
    // than its radius (slack included) plus the reach holds no near vertex.
    const Vec3 xc = qt.bones[cl.bone] * cl.center;
    const double motion_c = has_prev ? 2 * (xc - b.q_prev2->bones[cl.bone] * cl.center).norm() : 0.0;
    if (field_->distance(T_inv * xc) > cl.radius + options_.margin + motion_c + object_motion) continue;
    for (int v : cl.vertices) {
      const Vec3 x = vertices_.world_point(v, qt);
      const double motion = has_prev ? 2 * (x - vertices_.world_point(v, *b.q_prev2)).norm() : 0.0;
      const double reach = options_.margin + motion + object_motion;
      if (bounded) {
        const Vec3 lo = box.min.array() - reach, hi = box.max.array() + reach;
        if ((x.array() < lo.array()).any() || (x.array() > hi.array()).any()) continue;
      }
      const double phi = field_->distance(T_inv * x);
      if (phi < reach) near.push_back(v), near_phi.push_back(phi);
    }
  }
  std::vector<size_t> order(near.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](size_t i, size_t j) { return near[i] < near[j]; });
  {
    std::vector<int> n2;
    std::vector<double> p2;
    for (size_t i : order) n2.push_back(near[i]), p2.push_back(near_phi[i]);
    near.swap(n2);
    near_phi.swap(p2);
  }
}

/// The candidate faces (every skin face of a near vertex), their samples and
/// their distinct vertices.
void ContactPatchTerm::collect_candidate_faces(TermCache& cache, const std::vector<int>& near) const {
  PatchCache& c = static_cast<PatchCache&>(cache);
  const Avatar& a = *avatar_;
  std::vector<char> face_mark(a.surface_faces.rows(), 0);
  c.faces.clear();
  for (int v : near)
    for (int fc : vertex_faces_[v])
      if (!face_mark[fc]) face_mark[fc] = 1, c.faces.push_back(fc);
  std::sort(c.faces.begin(), c.faces.end());
  c.samples.clear();
  c.face_first.assign(1, 0);
  c.vertices.clear();
  c.vertex_slot.clear();
  for (int fc : c.faces) {
    append_face_samples(a.surface_rest, a.surface_faces, fc, options_.spacing, c.samples);
    c.face_first.push_back(int(c.samples.size()));
    for (int i = 0; i < 3; ++i) {
      const int v = a.surface_faces(fc, i);
      if (c.vertex_slot.emplace(v, int(c.vertices.size())).second) c.vertices.push_back(v);
    }
  }
}

void ContactPatchTerm::prepare_friction(const StepContext& ctx, TermCache& cache, const Configuration& qt) const {
  PatchCache& c = static_cast<PatchCache&>(cache);
  const size_t ns = c.samples.size();
  c.friction_bound.assign(ns, 0.0);
  c.friction_normal.assign(ns, Vec3::Zero());
  c.friction_point.assign(ns, Vec3::Zero());
  c.face_friction.assign(c.faces.size(), 0);
  if (!(options_.friction > 0) || !field_ || ns == 0) return;
  // The field where the broad phase placed it (a kinematic object's pose at
  // t + h, a dynamic one's at t, as sdf_contact.cpp) and, for a kinematic
  // object, its motion over the step.
  const Isometry& T = c.field_pose;
  const Isometry T_inv = T.inverse();
  Vec3 v = Vec3::Zero(), w = Vec3::Zero(), origin = T.translation();
  if (dynamic_) {
    c.object_t = ctx.bound[1].q_prev->bones[0];
  } else {
    const WorldFrame& f = *ctx.frame();
    v = f.linear_velocity, w = f.angular_velocity;
    origin = f.pose.translation() - v * ctx.h;  // the frame's origin at t
  }
  std::vector<Vec3> xv(c.vertices.size());
  for (size_t i = 0; i < xv.size(); ++i) xv[i] = patched_vertex(*avatar_, vertices_, c, c.vertices[i], qt, c.du).x;
  for (size_t fi = 0; fi < c.faces.size(); ++fi) {
    std::array<int, 3> vs;
    for (int i = 0; i < 3; ++i) vs[i] = c.vertex_slot.at(avatar_->surface_faces(c.faces[fi], i));
    for (int s = c.face_first[fi]; s < c.face_first[fi + 1]; ++s) {
      const SkinFaceSample& smp = c.samples[size_t(s)];
      const Vec3 x = smp.lambda[0] * xv[size_t(vs[0])] + smp.lambda[1] * xv[size_t(vs[1])] + smp.lambda[2] * xv[size_t(vs[2])];
      const geometry::SdfSample sd = field_->evaluate(T_inv * x);
      if (!(sd.distance < 0)) continue;
      c.friction_bound[size_t(s)] = options_.friction * options_.pressure_stiffness * smp.area * -sd.distance;
      c.friction_normal[size_t(s)] = (T.linear() * sd.gradient).normalized();
      c.friction_point[size_t(s)] = dynamic_ ? x : Vec3(x + ctx.h * (v + w.cross(x - origin)));
      c.face_friction[fi] = 1;
    }
  }
}

}  // namespace sflsh
