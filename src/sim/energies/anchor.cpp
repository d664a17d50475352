#include "sflsh/sim/energies/anchor.hpp"

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
};

const AnchorCache& anchor_cache(const StepContext& ctx, const std::string& name) {
  require(ctx.cache != nullptr, name, ": no cache (call begin_step through begin_term_step or the integrator)");
  return static_cast<const AnchorCache&>(*ctx.cache);
}

std::string anchor_prefix(const std::string& tool) { return tool + "/anchor/"; }

}  // namespace

std::string anchor_frame_name(const std::string& tool, int point) { return anchor_prefix(tool) + std::to_string(point); }

void add_anchor_frames(const std::string& tool, const WorldFrame& tool_frame, const std::vector<Anchor>& anchors,
                       bool dynamic_tool, std::map<std::string, WorldFrame>& frames) {
  const std::string prefix = anchor_prefix(tool);
  for (auto it = frames.lower_bound(prefix); it != frames.end() && it->first.compare(0, prefix.size(), prefix) == 0;)
    it = frames.erase(it);
  const Vec3 o = tool_frame.pose.translation();
  for (const Anchor& a : anchors) {
    WorldFrame f;
    f.pose.translation() = tool_frame.pose * a.offset;
    if (!dynamic_tool)
      f.linear_velocity = tool_frame.linear_velocity + tool_frame.angular_velocity.cross(f.pose.translation() - o);
    frames[anchor_frame_name(tool, a.point)] = f;
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
  if (!ctx.frames) return;
  const Configuration& qt = ctx.bound.empty() ? ctx.q_prev : *ctx.bound[0].q_prev;
  const std::string prefix = anchor_prefix(tool_);
  for (auto it = ctx.frames->lower_bound(prefix);
       it != ctx.frames->end() && it->first.compare(0, prefix.size(), prefix) == 0; ++it) {
    const std::string digits = it->first.substr(prefix.size());
    require(!digits.empty() && digits.size() < 10 && digits.find_first_not_of("0123456789") == std::string::npos,
            name(), ": world frame '", it->first, "': expected '", prefix, "<point index>'");
    const int p = std::stoi(digits);
    require(p < points_.size(), name(), ": world frame '", it->first, "': point ", p, " out of range (", points_.size(),
            " points)");
    const WorldFrame& f = it->second;
    require(f.pose.translation().allFinite() && f.linear_velocity.allFinite(), name(), ": world frame '", it->first,
            "' is not finite");
    c.points.push_back(p);
    c.x_t.push_back(points_.world_point(p, qt));
    if (dynamic_) {
      c.a_t.push_back(f.pose.translation());
      c.target.push_back(ctx.bound[1].q_prev->bones[0].inverse() * f.pose.translation());
    } else {
      c.target.push_back(f.pose.translation());
      c.a_t.push_back(f.pose.translation() - ctx.h * f.linear_velocity);
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
