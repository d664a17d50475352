#include "sflsh/sim/energies/sdf_contact.hpp"

#include <cmath>
#include <algorithm>
#include <array>
#include <map>
#include <tuple>

#include "sflsh/core/error.hpp"
#include "sflsh/core/rotation.hpp"
#include "sim/energies/lagged_friction.hpp"

namespace sflsh {
namespace {

struct ContactCache : TermCache {
  std::vector<int> candidates;
  Isometry frame_pose = Isometry::Identity();  // static/kinematic: the field's pose at t + h
  /// Friction, per candidate (lagged at time t): normal force, normal, position,
  /// and (kinematic objects) where the object carries that point by t + h.
  std::vector<double> lambda;
  std::vector<Vec3> normal, x_t, carried;
  Isometry object_t = Isometry::Identity();    // dynamic: the object's body pose at t
  Isometry shape_in_frame = Isometry::Identity();  // dynamic: this step's shape-in-body transform
};

ContactCache& contact_cache(const StepContext& ctx, const std::string& name) {
  require(ctx.cache != nullptr, name, ": no cache (call begin_step through begin_term_step or the integrator)");
  return static_cast<ContactCache&>(*ctx.cache);
}

/// Rotation angle (rad) of R.
double rotation_angle(const Mat3& R) { return std::acos(std::clamp((R.trace() - 1.0) / 2.0, -1.0, 1.0)); }

}  // namespace

SdfContactTerm::SdfContactTerm(std::string object, PosedPoints samples, geometry::SdfPtr field,
                               const Isometry& shape_in_frame, bool dynamic_object, const SdfContactOptions& o)
    : object_(std::move(object)),
      samples_(std::move(samples)),
      field_(std::move(field)),
      shape_in_frame_(shape_in_frame),
      dynamic_(dynamic_object),
      options_(o) {
  require(field_ != nullptr, "contact with '", object_, "': no field");
  require(o.stiffness >= 0 && std::isfinite(o.stiffness), "contact with '", object_, "': stiffness ", o.stiffness,
          " N/m, expected >= 0");
  require(o.friction >= 0 && std::isfinite(o.friction) && o.static_slip_speed > 0, "contact with '", object_,
          "': friction must be >= 0 and the static slip speed > 0");
  require(o.margin >= 0 && o.cluster_slack >= 0 && o.cluster_size > 0, "contact with '", object_,
          "': margin, slack must be >= 0 and the cluster size > 0");
  // Clusters: samples by dominant bone and unposed cell.
  std::map<std::tuple<int, long, long, long>, std::vector<int>> cells;
  for (int p = 0; p < samples_.size(); ++p) {
    const Vec3 x = samples_.unposed().row(p).transpose();
    cells[{samples_.dominant_bone(p), std::lround(std::floor(x.x() / o.cluster_size)),
           std::lround(std::floor(x.y() / o.cluster_size)), std::lround(std::floor(x.z() / o.cluster_size))}]
        .push_back(p);
  }
  for (auto& [key, members] : cells) {
    Cluster c;
    c.bone = std::get<0>(key);
    for (int p : members) c.center += samples_.unposed().row(p).transpose();
    c.center /= double(members.size());
    for (int p : members) c.radius = std::max(c.radius, (samples_.unposed().row(p).transpose() - c.center).norm());
    c.radius += o.cluster_slack;
    c.samples = std::move(members);
    clusters_.push_back(std::move(c));
  }
}

std::unique_ptr<TermCache> SdfContactTerm::make_cache() const { return std::make_unique<ContactCache>(); }

const std::vector<int>& SdfContactTerm::candidates(const StepContext& ctx) const {
  return contact_cache(ctx, name()).candidates;
}

Isometry SdfContactTerm::field_pose(const StepContext& ctx) const {
  if (!dynamic_) return contact_cache(ctx, name()).frame_pose;
  require(ctx.bound.size() == 2 && ctx.bound[1].q != nullptr, name(), ": the object's body is not bound");
  return ctx.bound[1].q->bones[0] * contact_cache(ctx, name()).shape_in_frame;
}

std::string moving_shape_frame_name(const std::string& object) { return object + "/shape"; }

Isometry step_shape_in_frame(const WorldFrame* f, const Isometry& body_t, const Isometry& fixed,
                             const std::string& term, const std::string& object) {
  if (!f) return fixed;
  require(f->pose.matrix().allFinite(), term, ": world frame '", moving_shape_frame_name(object), "' is not finite");
  return body_t.inverse() * f->pose;
}

std::vector<std::string> SdfContactTerm::input_frames() const {
  return {dynamic_ ? moving_shape_frame_name(object_) : object_};
}

void SdfContactTerm::begin_step(const StepContext& ctx) const {
  ContactCache& c = contact_cache(ctx, name());
  c.candidates.clear();
  // The field's pose at time t (the broad phase's reference) and how far the
  // object may move over the step.
  const geometry::Aabb local = field_->bounds();
  const double extent = !local.is_unbounded() ? 0.5 * (local.max - local.min).norm() : 1.0;
  Isometry T;
  double object_motion = 0;
  if (dynamic_) {
    require(ctx.bound.size() == 2, name(), ": a dynamic object's contact is bound to the body and the object");
    const Isometry& G = ctx.bound[1].q_prev->bones[0];
    // A shape that moves on its body (a gripper's jaw): its pose for this step.
    c.shape_in_frame = step_shape_in_frame(ctx.frame(), G, shape_in_frame_, name(), object_);
    T = G * c.shape_in_frame;
    if (ctx.bound[1].q_prev2 && !ctx.bound[1].q_prev2->bones.empty()) {
      const Isometry& Gp = ctx.bound[1].q_prev2->bones[0];
      object_motion = 2 * ((G.translation() - Gp.translation()).norm() +
                           rotation_angle(G.linear() * Gp.linear().transpose()) * extent);
    }
  } else {
    require(ctx.frame() != nullptr, name(), ": the step inputs have no world frame '", object_, "'");
    const WorldFrame& f = *ctx.frame();
    T = f.pose * shape_in_frame_;
    c.frame_pose = T;
    object_motion = ctx.h * (f.linear_velocity.norm() + f.angular_velocity.norm() * extent);
  }
  const Isometry T_inv = T.inverse();
  const BoundBody& b = ctx.bound.empty() ? BoundBody{0, 0, ctx.avatar, ctx.layout, nullptr, &ctx.q_prev, &ctx.q_prev2}
                                         : ctx.bound[0];
  const Configuration& qt = *b.q_prev;
  const bool has_prev = b.q_prev2 && b.q_prev2->bones.size() == qt.bones.size();
  for (const Cluster& cl : clusters_) {
    const Vec3 x = qt.bones[cl.bone] * cl.center;
    const double motion = has_prev ? 2 * (x - b.q_prev2->bones[cl.bone] * cl.center).norm() : 0.0;
    const double reach = options_.margin + motion + object_motion;
    if (field_->distance(T_inv * x) > cl.radius + reach) continue;
    for (int p : cl.samples)
      if (field_->distance(T_inv * samples_.world_point(p, qt)) < reach) c.candidates.push_back(p);
  }
  // Friction data at time t (header comment).
  const size_t n = c.candidates.size();
  c.lambda.assign(n, 0.0);
  c.normal.assign(n, Vec3::Zero());
  c.x_t.assign(n, Vec3::Zero());
  c.carried.assign(n, Vec3::Zero());
  if (options_.friction <= 0) return;
  if (dynamic_) c.object_t = ctx.bound[1].q_prev->bones[0];
  Vec3 v = Vec3::Zero(), w = Vec3::Zero(), origin = T.translation();
  if (!dynamic_) {
    const WorldFrame& f = *ctx.frame();
    v = f.linear_velocity, w = f.angular_velocity;
    origin = f.pose.translation() - v * ctx.h;  // the frame's origin at t
  }
  for (size_t i = 0; i < n; ++i) {
    const Vec3 x = samples_.world_point(c.candidates[i], qt);
    const geometry::SdfSample sd = field_->evaluate(T_inv * x);
    if (!(sd.distance < 0)) continue;
    c.lambda[i] = options_.stiffness * -sd.distance;
    c.normal[i] = (T.linear() * sd.gradient).normalized();
    c.x_t[i] = x;
    c.carried[i] = x + ctx.h * (v + w.cross(x - origin));
  }
}

bool SdfContactTerm::active(const StepContext& ctx) const { return !candidates(ctx).empty(); }

double SdfContactTerm::compute(const StepContext& ctx, const Configuration& q, VecRef* grad, MatRef* hess) const {
  const std::vector<int>& cand = candidates(ctx);
  const Isometry T = field_pose(ctx);
  const Isometry T_inv = T.inverse();
  const DofLayout& L = ctx.bound.empty() ? ctx.layout : ctx.bound[0].layout;
  const int ob = dynamic_ ? ctx.bound[1].layout.base : -1;
  const double k = options_.stiffness;
  double E = 0;
  const ContactCache& cc = contact_cache(ctx, name());
  const double mu = options_.friction, eps = options_.static_slip_speed * ctx.h;
  // A dynamic object carries the point it touched at t by G(q) G_t⁻¹.
  const Isometry carry = dynamic_ ? Isometry(ctx.bound[1].q->bones[0] * cc.object_t.inverse()) : Isometry::Identity();
  for (size_t i = 0; i < cand.size(); ++i) {
    const int p = cand[i];
    const Vec3 x = samples_.world_point(p, q);
    if (mu > 0 && cc.lambda[i] > 0) E += friction(ctx, q, p, x, cc.lambda[i], cc.normal[i],
                                                  dynamic_ ? Vec3(carry * cc.x_t[i]) : cc.carried[i], mu, eps, grad, hess);
    const geometry::SdfSample s = field_->evaluate(T_inv * x);
    const double d = s.distance;
    if (!(d < 0)) continue;
    E += 0.5 * k * d * d;
    if (!grad && !hess) continue;
    const Vec3 n = T.linear() * s.gradient;  // ∂φ/∂x, world
    // φ's gradient is n at x, and the object's point there is x itself.
    add_point_derivatives(q, L, p, k * d * n, k * n * n.transpose(), ob, x, grad, hess);
  }
  return E;
}

void SdfContactTerm::add_point_derivatives(const Configuration& q, const DofLayout& L, int p, const Vec3& g,
                                           const Mat3& H, int ob, const Vec3& y, VecRef* grad, MatRef* hess) const {
  // r = x_p(q) − y(q_object): ∂r/∂δ = [J_p | −J_o], by blocks (posed_points.hpp):
  // bone j (if dynamic) [−[p_j]×, w_j I] with p_j = w_j G_j ȳ (ȳ = x̄ + U z),
  // handle h: w_h A with A = Σ_j w_j R_j, and the object's point
  // J_o = [−[y]×, I] (it moves by ω × y + v). Adds Jᵀg and JᵀHJ block by block
  // (fixed-size 6x6, 6x3, 3x3), so the cost is (6 n_b + 3 n_h)² without indirection.
  using Mat36 = Eigen::Matrix<double, 3, 6>;
  constexpr int kMaxBones = 24;  // SMPL's skeleton; a skin point has a few with weight
  const PosedPoints::Rows r = samples_.rows(p);
  const int nb = L.bones_dynamic ? r.num_bones : 0;
  require(nb <= kMaxBones, name(), ": a skin sample has ", nb, " bones, at most ", kMaxBones, " are supported");
  const Vec3 yb = samples_.unposed_displaced(p, q.z);
  std::array<Mat36, kMaxBones> Jb;
  std::array<int, kMaxBones> col;
  Mat3 A = Mat3::Zero();
  for (int e = 0; e < r.num_bones; ++e) {
    const Isometry& G = q.bones[r.bones[e]];
    const double w = r.bone_weights[e];
    A += w * G.linear();
    if (e < nb) {
      Jb[e] << -hat(w * (G * yb)), w * Mat3::Identity();
      col[e] = L.bone_offset(r.bones[e]);
    }
  }
  Mat36 Jo;
  if (ob >= 0) Jo << -hat(y), Mat3::Identity();
  const int z0 = L.z_offset();
  if (grad) {
    for (int i = 0; i < nb; ++i) grad->segment<6>(col[i]) += Jb[i].transpose() * g;
    const Vec3 Atg = A.transpose() * g;
    for (int h = 0; h < r.num_handles; ++h) grad->segment<3>(z0 + 3 * r.handles[h]) += r.handle_weights[h] * Atg;
    if (ob >= 0) grad->segment<6>(ob) -= Jo.transpose() * g;
  }
  if (!hess) return;
  const Mat3 HA = H * A, AHA = A.transpose() * HA;
  const Mat36 HJo = H * Jo;
  for (int h = 0; h < r.num_handles; ++h) {
    const int zh = z0 + 3 * r.handles[h];
    const double wh = r.handle_weights[h];
    for (int l = 0; l < r.num_handles; ++l)
      hess->block<3, 3>(zh, z0 + 3 * r.handles[l]) += (wh * r.handle_weights[l]) * AHA;
    for (int i = 0; i < nb; ++i) {
      const Eigen::Matrix<double, 6, 3> c = wh * (Jb[i].transpose() * HA);
      hess->block<6, 3>(col[i], zh) += c;
      hess->block<3, 6>(zh, col[i]) += c.transpose();
    }
    if (ob >= 0) {
      const Eigen::Matrix<double, 6, 3> c = -wh * (Jo.transpose() * HA);
      hess->block<6, 3>(ob, zh) += c;
      hess->block<3, 6>(zh, ob) += c.transpose();
    }
  }
  for (int i = 0; i < nb; ++i) {
    const Mat36 HJi = H * Jb[i];
    for (int j = 0; j < nb; ++j) hess->block<6, 6>(col[j], col[i]) += Jb[j].transpose() * HJi;
    if (ob >= 0) {
      const Eigen::Matrix<double, 6, 6> c = -(Jo.transpose() * HJi);
      hess->block<6, 6>(ob, col[i]) += c;
      hess->block<6, 6>(col[i], ob) += c.transpose();
    }
  }
  if (ob >= 0) hess->block<6, 6>(ob, ob) += Jo.transpose() * HJo;
}

double SdfContactTerm::friction(const StepContext& ctx, const Configuration& q, int p, const Vec3& x, double lambda,
                                const Vec3& n, const Vec3& y, double mu, double eps, VecRef* grad, MatRef* hess) const {
  const contact_friction::PointFriction f = contact_friction::point_friction(x, y, n, mu * lambda, eps, grad || hess);
  if (!grad && !hess) return f.energy;
  const DofLayout& L = ctx.bound.empty() ? ctx.layout : ctx.bound[0].layout;
  add_point_derivatives(q, L, p, f.gradient, f.hessian, dynamic_ ? ctx.bound[1].layout.base : -1, y, grad, hess);
  return f.energy;
}

std::vector<TermQuantity> SdfContactTerm::report(const StepContext& ctx, const Configuration& q) const {
  const Isometry T = field_pose(ctx);
  const Isometry T_inv = T.inverse();
  Vec3 force = Vec3::Zero(), friction_force = Vec3::Zero();
  int active = 0;
  double depth = 0;
  const ContactCache& cc = contact_cache(ctx, name());
  const std::vector<int>& cand = candidates(ctx);
  if (options_.friction > 0) {
    // −∂D/∂x of every sample with a lagged normal force: D's gradient on the
    // body's translation (the bones' v columns sum ∂x/∂v = I for each sample).
    const Isometry carry = dynamic_ ? Isometry(ctx.bound[1].q->bones[0] * cc.object_t.inverse()) : Isometry::Identity();
    const double eps = options_.static_slip_speed * ctx.h;
    for (size_t i = 0; i < cand.size(); ++i) {
      if (!(cc.lambda[i] > 0)) continue;
      const Vec3 y = dynamic_ ? Vec3(carry * cc.x_t[i]) : cc.carried[i];
      friction_force -= contact_friction::point_friction(samples_.world_point(cand[i], q), y, cc.normal[i],
                                                         options_.friction * cc.lambda[i], eps, true)
                            .gradient;
    }
  }
  force += friction_force;
  Vec3 point = Vec3::Zero();
  double weight = 0;
  for (int p : cand) {
    const Vec3 x = samples_.world_point(p, q);
    const geometry::SdfSample s = field_->evaluate(T_inv * x);
    if (!(s.distance < 0)) continue;
    force -= options_.stiffness * s.distance * (T.linear() * s.gradient);
    ++active;
    depth = std::max(depth, -s.distance);
    // The active samples' mean, weighted by their normal force k|d|.
    point -= s.distance * x;
    weight -= s.distance;
  }
  std::vector<TermQuantity> out = {{"force", "N", force}, {"friction_force", "N", friction_force},
                                   {"active_samples", "", VecX::Constant(1, active)},
                                   {"max_penetration", "m", VecX::Constant(1, depth)}};
  if (weight > 0) out.push_back({"contact_point", "m", point / weight});
  return out;
}

PosedPoints skin_contact_samples(const Avatar& avatar, double spacing, int max_handles, double* max_dropped) {
  PosedPoints all = PosedPoints::at_surface(avatar);
  if (max_handles > 0) all = all.with_truncated_rows(max_handles, max_dropped);
  if (!(spacing > 0)) return all;
  // One vertex per cell: the one nearest the cell's centre.
  std::map<std::tuple<long, long, long>, std::pair<double, int>> best;
  for (int p = 0; p < all.size(); ++p) {
    const Vec3 x = all.unposed().row(p).transpose();
    const Vec3 cell = (x / spacing).array().floor();
    const double d = (x - (cell.array() + 0.5).matrix() * spacing).squaredNorm();
    auto [it, fresh] = best.try_emplace({long(cell.x()), long(cell.y()), long(cell.z())}, d, p);
    if (!fresh && d < it->second.first) it->second = {d, p};
  }
  std::vector<int> rows;
  for (const auto& [cell, dp] : best) rows.push_back(dp.second);
  std::sort(rows.begin(), rows.end());
  return all.subset(rows);
}

}  // namespace sflsh
