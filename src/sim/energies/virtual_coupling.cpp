#include "sflsh/sim/energies/virtual_coupling.hpp"

#include <cmath>

#include <Eigen/Eigenvalues>

#include "sflsh/core/error.hpp"
#include "sflsh/core/rotation.hpp"

namespace sflsh {
namespace {

struct CouplingCache : TermCache {
  Vec3 d = Vec3::Zero(), d_t = Vec3::Zero(), c_t = Vec3::Zero(), omega_d = Vec3::Zero();
  Mat3 R_d = Mat3::Identity(), R_t = Mat3::Identity();
};

const CouplingCache& coupling_cache(const StepContext& ctx, const std::string& name) {
  require(ctx.cache != nullptr, name, ": no cache (call begin_step through begin_term_step or the integrator)");
  return static_cast<const CouplingCache&>(*ctx.cache);
}

/// J_l⁻¹(φ): ∂ log(exp(δ) exp(φ)) / ∂δ at δ = 0.
Mat3 left_jacobian_inverse(const Vec3& phi) {
  const double th = phi.norm();
  const Mat3 P = hat(phi);
  const double a = th < 1e-4 ? 1.0 / 12.0 + th * th / 720.0
                             : 1.0 / (th * th) - (1.0 + std::cos(th)) / (2.0 * th * std::sin(th));
  return Mat3::Identity() - 0.5 * P + a * P * P;
}

/// The parts of the energy at G: translation residuals and rotation terms.
struct CouplingParts {
  Vec3 r, s;             ///< c − d and (c − c_t) − (d − d_t)
  Mat3 M;                ///< R R_dᵀ
  Vec3 phi, e;           ///< log(R R_tᵀ) and φ − h ω_d
  double E = 0;
};

}  // namespace

std::string device_frame_name(const std::string& tool) { return tool + "/device"; }

VirtualCouplingTerm::VirtualCouplingTerm(std::string tool, const VirtualCouplingOptions& o)
    : tool_(std::move(tool)), options_(o) {
  require(o.stiffness > 0 && std::isfinite(o.stiffness), "coupling of '", tool_, "': stiffness ", o.stiffness,
          " N/m, expected > 0");
  require(o.rotational_stiffness > 0 && std::isfinite(o.rotational_stiffness), "coupling of '", tool_,
          "': rotational stiffness ", o.rotational_stiffness, " N·m/rad, expected > 0");
  require(o.damping >= 0 && std::isfinite(o.damping), "coupling of '", tool_, "': damping ", o.damping,
          " N·s/m, expected >= 0");
  require(o.rotational_damping >= 0 && std::isfinite(o.rotational_damping), "coupling of '", tool_,
          "': rotational damping ", o.rotational_damping, " N·m·s/rad, expected >= 0");
}

std::unique_ptr<TermCache> VirtualCouplingTerm::make_cache() const { return std::make_unique<CouplingCache>(); }

void VirtualCouplingTerm::begin_step(const StepContext& ctx) const {
  require(ctx.cache != nullptr, name(), ": no cache");
  CouplingCache& c = static_cast<CouplingCache&>(*ctx.cache);
  require(ctx.frame() != nullptr, name(), ": the step has no world frame '", device_frame_name(tool_), "'");
  const WorldFrame& f = *ctx.frame();
  require(f.pose.matrix().allFinite() && f.linear_velocity.allFinite() && f.angular_velocity.allFinite(), name(),
          ": world frame '", device_frame_name(tool_), "' is not finite");
  require(ctx.q_prev.bones.size() == 1, name(), ": the tool must be a rigid body (one bone)");
  c.d = f.pose.translation();
  c.R_d = f.pose.linear();
  c.d_t = c.d - ctx.h * f.linear_velocity;
  c.omega_d = f.angular_velocity;
  c.c_t = ctx.q_prev.bones[0].translation();
  c.R_t = ctx.q_prev.bones[0].linear();
}

namespace {

CouplingParts coupling_parts(const CouplingCache& c, const VirtualCouplingOptions& o, double h, const Isometry& G) {
  CouplingParts p;
  const Vec3 x = G.translation();
  const Mat3 R = G.linear();
  p.r = x - c.d;
  p.s = (x - c.c_t) - (c.d - c.d_t);
  p.M = R * c.R_d.transpose();
  p.phi = rotation_log(R * c.R_t.transpose());
  p.e = p.phi - h * c.omega_d;
  p.E = 0.5 * o.stiffness * p.r.squaredNorm() + 0.5 * (o.damping / h) * p.s.squaredNorm() +
        0.5 * o.rotational_stiffness * (3.0 - p.M.trace()) + 0.5 * (o.rotational_damping / h) * p.e.squaredNorm();
  return p;
}

/// ∂E/∂ω of the rotation terms (world ω, left perturbation).
Vec3 rotation_gradient(const CouplingParts& p, const VirtualCouplingOptions& o, double h, Mat3* J) {
  const Mat3& M = p.M;
  const Vec3 spring = -0.5 * o.rotational_stiffness * Vec3(M(1, 2) - M(2, 1), M(2, 0) - M(0, 2), M(0, 1) - M(1, 0));
  *J = left_jacobian_inverse(p.phi);
  return spring + (o.rotational_damping / h) * J->transpose() * p.e;
}

}  // namespace

double VirtualCouplingTerm::compute(const StepContext& ctx, const Configuration& q, VecRef* grad,
                                    MatRef* hess) const {
  const CouplingCache& c = coupling_cache(ctx, name());
  const VirtualCouplingOptions& o = options_;
  const double h = ctx.h;
  const CouplingParts p = coupling_parts(c, o, h, q.bones[0]);
  if (!grad && !hess) return p.E;
  const int b = ctx.layout.bone_offset(0);
  const Vec3 x = q.bones[0].translation();
  Eigen::Matrix<double, 3, 6> Jx;  // ∂c/∂(ω, v)
  Jx << -hat(x), Mat3::Identity();
  Mat3 Jr;
  const Vec3 g_rot = rotation_gradient(p, o, h, &Jr);
  if (grad) {
    const Vec3 g = o.stiffness * p.r + (o.damping / h) * p.s;
    grad->segment<6>(b) += Jx.transpose() * g;
    grad->segment<3>(b) += g_rot;
  }
  if (hess) {
    hess->block<6, 6>(b, b) += (o.stiffness + o.damping / h) * Jx.transpose() * Jx;
    Mat3 Hs = 0.5 * o.rotational_stiffness * (p.M.trace() * Mat3::Identity() - 0.5 * (p.M + p.M.transpose()));
    Eigen::SelfAdjointEigenSolver<Mat3> eig(Hs);
    Hs = eig.eigenvectors() * eig.eigenvalues().cwiseMax(0.0).asDiagonal() * eig.eigenvectors().transpose();
    hess->block<3, 3>(b, b) += Hs + (o.rotational_damping / h) * Jr.transpose() * Jr;
  }
  return p.E;
}

std::vector<TermQuantity> VirtualCouplingTerm::report(const StepContext& ctx, const Configuration& q) const {
  const CouplingCache& c = coupling_cache(ctx, name());
  const CouplingParts p = coupling_parts(c, options_, ctx.h, q.bones[0]);
  Mat3 J;
  const Vec3 force = -(options_.stiffness * p.r + (options_.damping / ctx.h) * p.s);
  const Vec3 torque = -rotation_gradient(p, options_, ctx.h, &J);
  return {{"force", "N", force},
          {"torque", "N·m", torque},
          {"offset", "m", VecX::Constant(1, p.r.norm())},
          {"angle", "rad", VecX::Constant(1, rotation_log(p.M).norm())}};
}

}  // namespace sflsh
