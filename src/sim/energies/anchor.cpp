#include "sflsh/sim/energies/anchor.hpp"

#include <algorithm>
#include <cmath>

#include "sflsh/core/error.hpp"
#include "sflsh/core/rotation.hpp"

namespace sflsh {
namespace {

struct AnchorCache : TermCache {
  std::vector<int> points;
  /// Kinematic tool: a_p at t + h; dynamic tool: the offset o_p in the tool's body frame.
  std::vector<Vec3> target;
  std::vector<Vec3> a_t, x_t;  // tool and flesh points at time t (step frame)
  std::vector<int> order;      // the step's anchors (indices into ctx.anchors) by increasing point
};

const AnchorCache& anchor_cache(const StepContext& ctx, const std::string& name) {
  require(ctx.cache != nullptr, name, ": no cache (call begin_step through begin_term_step or the integrator)");
  return static_cast<const AnchorCache&>(*ctx.cache);
}

}  // namespace

void anchor_points(const WorldFrame& tool_frame, const std::vector<Anchor>& anchors, bool dynamic_tool,
                   std::vector<AnchorPoint>& points) {
  points.clear();
  const Vec3 o = tool_frame.pose.translation();
  for (const Anchor& a : anchors) {
    AnchorPoint p;
    p.point = a.point;
    p.position = tool_frame.pose * a.offset;
    if (!dynamic_tool) p.velocity = tool_frame.linear_velocity + tool_frame.angular_velocity.cross(p.position - o);
    points.push_back(p);
  }
}

AnchorTerm::AnchorTerm(std::string tool, PosedPoints points, bool dynamic_tool, const AnchorOptions& o)
    : tool_(std::move(tool)), points_(std::move(points)), dynamic_(dynamic_tool), options_(o) {
  require(o.hardness > 0 && std::isfinite(o.hardness), "anchors of '", tool_, "': hardness ", o.hardness,
          " N/m, expected > 0");
  require(o.damping >= 0 && std::isfinite(o.damping), "anchors of '", tool_, "': damping ", o.damping,
          " N·s/m, expected >= 0");
}

std::unique_ptr<TermCache> AnchorTerm::make_cache() const { return std::make_unique<AnchorCache>(); }

void AnchorTerm::begin_step(const StepContext& ctx) const {
  require(ctx.cache != nullptr, name(), ": no cache");
  AnchorCache& c = static_cast<AnchorCache&>(*ctx.cache);
  c.points.clear(), c.target.clear(), c.a_t.clear(), c.x_t.clear();
  if (dynamic_) require(ctx.bound.size() == 2, name(), ": a dynamic tool's anchors are bound to the body and the tool");
  if (!ctx.anchors) return;
  const Configuration& qt = ctx.bound.empty() ? ctx.q_prev : *ctx.bound[0].q_prev;
  // By increasing point, one anchor per point (the last given): the sums over
  // anchors do not depend on the order the tool lists them in.
  const std::vector<AnchorPoint>& given = *ctx.anchors;
  c.order.resize(given.size());
  for (size_t i = 0; i < given.size(); ++i) c.order[i] = int(i);
  std::stable_sort(c.order.begin(), c.order.end(), [&](int i, int j) { return given[i].point < given[j].point; });
  for (size_t k = 0; k < c.order.size(); ++k) {
    const AnchorPoint& a = given[size_t(c.order[k])];
    if (k + 1 < c.order.size() && given[size_t(c.order[k + 1])].point == a.point) continue;
    const int p = a.point;
    require(p >= 0 && p < points_.size(), name(), ": anchored point ", p, " out of range (", points_.size(),
            " points)");
    require(a.position.allFinite() && a.velocity.allFinite(), name(), ": anchored point ", p, " is not finite");
    const Vec3 position = a.position - ctx.frame_origin;  // the step frame
    c.points.push_back(p);
    c.x_t.push_back(points_.world_point(p, qt));
    if (dynamic_) {
      c.a_t.push_back(position);
      c.target.push_back(ctx.bound[1].q_prev->bones[0].inverse() * position);
    } else {
      c.target.push_back(position);
      c.a_t.push_back(position - ctx.h * a.velocity);
    }
  }
}

bool AnchorTerm::active(const StepContext& ctx) const { return !anchor_cache(ctx, name()).points.empty(); }

std::vector<int> AnchorTerm::anchored_points(const StepContext& ctx) const { return anchor_cache(ctx, name()).points; }

Vec3 AnchorTerm::tool_point(const StepContext& ctx, int i) const {
  const AnchorCache& c = anchor_cache(ctx, name());
  if (!dynamic_) return c.target.at(i);
  require(ctx.bound.size() == 2 && ctx.bound[1].q != nullptr, name(), ": the tool's body is not bound");
  return ctx.bound[1].q->bones[0] * c.target.at(i);
}

double AnchorTerm::compute(const StepContext& ctx, const Configuration& q, VecRef* grad, MatRef* hess) const {
  const AnchorCache& c = anchor_cache(ctx, name());
  const DofLayout& L = ctx.bound.empty() ? ctx.layout : ctx.bound[0].layout;
  const int ob = dynamic_ ? ctx.bound[1].layout.base : -1;
  const double k = options_.hardness, cd = options_.damping / ctx.h, kappa = k + cd;
  Eigen::Matrix<double, 3, Eigen::Dynamic> J;
  std::vector<int> cols;
  double E = 0;
  for (size_t i = 0; i < c.points.size(); ++i) {
    const int p = c.points[i];
    const Vec3 x = points_.world_point(p, q), a = tool_point(ctx, int(i));
    const Vec3 r = x - a, d = (x - c.x_t[i]) - (a - c.a_t[i]);
    E += 0.5 * k * r.squaredNorm() + 0.5 * cd * d.squaredNorm();
    if (!grad && !hess) continue;
    // D = ∂(x − a)/∂δ = [J_x | −J_a], J_a = [−[a]×, I] on the tool's 6 DoFs.
    points_.local_jacobian(p, q, L, J, cols);
    const int m = int(cols.size());
    Eigen::Matrix<double, 3, 6> Ja;
    if (dynamic_) Ja << -hat(a), Mat3::Identity();
    if (grad) {
      const Vec3 g = k * r + cd * d;
      const VecX gb = J.transpose() * g;
      for (int e = 0; e < m; ++e) (*grad)[cols[e]] += gb[e];
      if (dynamic_) grad->segment<6>(ob) -= Ja.transpose() * g;
    }
    if (hess) {
      const MatX Hbb = kappa * (J.transpose() * J);
      for (int e = 0; e < m; ++e)
        for (int f = 0; f < m; ++f) (*hess)(cols[e], cols[f]) += Hbb(e, f);
      if (dynamic_) {
        hess->block<6, 6>(ob, ob) += kappa * Ja.transpose() * Ja;
        const Eigen::Matrix<double, 6, Eigen::Dynamic> Hob = -kappa * (Ja.transpose() * J);
        for (int e = 0; e < m; ++e)
          for (int row = 0; row < 6; ++row) {
            (*hess)(ob + row, cols[e]) += Hob(row, e);
            (*hess)(cols[e], ob + row) += Hob(row, e);
          }
      }
    }
  }
  return E;
}

std::vector<TermQuantity> AnchorTerm::report(const StepContext& ctx, const Configuration& q) const {
  const AnchorCache& c = anchor_cache(ctx, name());
  const int n = int(c.points.size());
  const double k = options_.hardness, cd = options_.damping / ctx.h;
  VecX forces(3 * n), points(n);
  Vec3 total = Vec3::Zero();
  double stretch = 0;
  for (int i = 0; i < n; ++i) {
    const Vec3 x = points_.world_point(c.points[i], q), a = tool_point(ctx, i);
    // −∂E_p/∂x: the spring and the damper's backward-Euler force.
    const Vec3 f = -(k * (x - a) + cd * ((x - c.x_t[i]) - (a - c.a_t[i])));
    forces.segment<3>(3 * i) = f;
    points[i] = c.points[i];
    total += f;
    stretch = std::max(stretch, (x - a).norm());
  }
  return {{"force", "N", total},
          {"anchor_forces", "N", forces},
          {"anchor_points", "", points},
          {"max_stretch", "m", VecX::Constant(1, stretch)}};
}

}  // namespace sflsh
