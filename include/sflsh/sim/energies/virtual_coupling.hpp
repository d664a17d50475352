#pragma once
// Virtual coupling (AMBF and haptic rendering): a tool that is a
// dynamic rigid body of the model (rigid_body_terms.hpp) is pulled towards
// its device's pose by a spring and a damper, as a term of the backward-Euler
// objective, so a stiff coupling stays stable and the tool cannot be pushed
// through the flesh by the device: contact and anchors act on the tool body,
// and the device only pulls on it.
//
// With the tool body's pose G = (R, c) (c: its frame origin, world) and the
// device pose D = (R_d, d) at t + h:
//   E = ½ k |c − d|² + ½ (c_t/h) |(c − c_t) − (d − d_t)|²            translation
//     + ½ k_r (3 − tr(R R_dᵀ)) + ½ (c_r/h) |log(R R_tᵀ) − h ω_d|²      rotation
// (c_t, R_t: the tool at time t; d_t = d − h v_d with v_d, ω_d the device
// frame's twist). ½ k_r (3 − tr(R R_dᵀ)) = k_r (1 − cos θ) ≈ ½ k_r θ² for the
// angle θ between tool and device. The dampers are the backward-Euler
// potentials of damping forces on the relative velocities. Gradient exact;
// Hessian: Gauss–Newton for the translation and the rotational damper
// (∂log/∂ω = J_l⁻¹), the exact second derivative of the trace term with its
// negative eigenvalues (angles beyond 90°) clamped to 0.
//
// The device's pose is the term's input frame, the world frame
// `device_frame_name(tool)` = "<tool>/device" of the step inputs: pose at
// t + h, twist (m/s, rad/s world) over the step.
// The term is bound to the tool body alone (its one bone, 6 DoFs).
#include <string>

#include "sflsh/sim/energy_term.hpp"

namespace sflsh {

/// "<tool>/device": the world frame carrying a coupled tool's device pose for a step.
std::string device_frame_name(const std::string& tool);

struct VirtualCouplingOptions {
  double stiffness = 2.0e4;           ///< k, N/m
  double damping = 50.0;              ///< c_t, N·s/m
  double rotational_stiffness = 20.0; ///< k_r, N·m/rad
  double rotational_damping = 0.2;    ///< c_r, N·m·s/rad
};

class VirtualCouplingTerm : public EnergyTerm {
 public:
  /// Throws on a non-positive stiffness or a negative damping.
  VirtualCouplingTerm(std::string tool, const VirtualCouplingOptions& options);
  std::string name() const override { return "coupling:" + tool_; }
  BodyBlocks blocks() const override { return BodyBlocks::Bones; }
  std::vector<std::string> input_frames() const override { return {device_frame_name(tool_)}; }
  std::unique_ptr<TermCache> make_cache() const override;
  /// Reads the device frame (throws naming it when it is missing or not finite).
  void begin_step(const StepContext& ctx) const override;
  double compute(const StepContext& ctx, const Configuration& q, VecRef* grad, MatRef* hess) const override;
  /// At q: "force" (3, N, world) and "torque" (3, N·m, world, about the
  /// tool's frame origin) the coupling exerts on the tool — the device feels
  /// their opposites —, "offset" (1, m: |c − d|) and "angle" (1, rad).
  std::vector<TermQuantity> report(const StepContext& ctx, const Configuration& q) const override;
  const VirtualCouplingOptions& options() const { return options_; }

 private:
  std::string tool_;
  VirtualCouplingOptions options_;
};

}  // namespace sflsh
