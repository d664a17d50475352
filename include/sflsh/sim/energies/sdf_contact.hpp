#pragma once
// Rigid ↔ flesh contact through a signed distance field (seed §5; DESIGN.md
// §4). Samples of the body's skin, embedded in their tets so that
// their world position x_p(q) follows the bones and the soft DoFs z
// (posed_points.hpp), are pushed out of a rigid object's field φ by a
// quadratic penalty on penetration:
//   E = Σ_p ½ k min(φ(x_p), 0)²,   φ(x) = φ_local(T⁻¹ x),  T = the object's pose.
// Gradient k φ ∇φᵀ J_p (exact); Hessian Gauss–Newton k J_pᵀ ∇φ ∇φᵀ J_p (PSD),
// J_p = ∂x_p/∂δ. It acts on the soft tissue directly and on the skeleton
// through the coupled solve.
//
// The object is either
//   * static or kinematic: the world frame `object` of the step inputs
//     (its input frame, StepInputs::frames) gives T at t + h; the term is
//     bound to the body alone;
//   * dynamic: a rigid-object body of the model (model.hpp), bound second;
//     T = G_object · shape_in_frame at the current iterate (a shape that
//     moves on its body, like a gripper's jaw, gives its pose for the step as
//     the world frame moving_shape_frame_name(object) = "<object>/shape":
//     G_t · S with G_t the body's pose at t and S the shape's pose in the
//     body at t + h; the term then uses S for the step), and the term also
//     fills the object's 6 DoFs: ∂φ/∂ω = −x × ∇φ, ∂φ/∂v = −∇φ (the tangent
//     of configuration.hpp: a point of the object moves by ω × x + v at first
//     order, whatever the pivot), so the forces on body and object are equal
//     and opposite and momentum is conserved.
//
// Friction (Coulomb, lagged per step; Li et al. 2020, "Incremental Potential
// Contact" §5): a sample in contact at time t, with normal force
// λ = k·max(0, −φ(x_t)) and normal n at x_t, gets the dissipative potential
//   D = μ λ f0(|s|),   s = (I − n nᵀ)(x(q) − y(q)),
// where y is where the object carries the point it touched at t (so s is the
// tangential slip over the step) and f0 the C¹ mollifier of |s| below
// ε = ε_v h (f0 = z²/ε − z³/(3ε²) + ε/3 for z < ε, z beyond): static friction
// as a stiff tangential spring up to μλ, sliding friction μλ against the
// slip beyond. Its Hessian μλ P[(f1/z) I + (f1′ − f1/z) ŝŝᵀ]P is PSD. λ, n,
// x_t are frozen for the step (begin_step), so a sample starts to feel
// friction one step after touching.
//
// Broad phase (begin_step): the samples are grouped into clusters (dominant
// bone × a cell of `cluster_size` in the unposed space) with a bounding
// sphere; a cluster is kept only if φ at its centre, carried by its bone at
// time t, is below its radius plus slack (skinning blend, soft displacement,
// the motion over the step); then each kept sample's exact position at t is
// tested against the margin. Newton iterations evaluate only these
// candidates, so the cost follows the samples near the object, not the skin size.
#include <string>
#include <vector>

#include "sflsh/geometry/sdf.hpp"
#include "sflsh/sim/energy_term.hpp"
#include "sflsh/sim/posed_points.hpp"

namespace sflsh {

struct SdfContactOptions {
  double stiffness = 2.0e4;  ///< k, N/m per sample
  /// Candidate margin (m): a sample enters the step's contact set when φ at
  /// time t is below margin + twice its displacement over the last step + the
  /// object's motion over the step, h (|v| + |ω| extent) for a kinematic object
  /// (extent: half its bounds' diagonal, 1 m when unbounded), twice its last
  /// step's for a dynamic one.
  double margin = 0.01;
  /// Broad-phase slack (m) added to every cluster's radius for linear blend
  /// skinning and soft displacement away from the dominant bone's rigid motion.
  double cluster_slack = 0.05;
  double cluster_size = 0.1;  ///< m, cluster cell in the unposed space
  double friction = 0.0;      ///< μ, Coulomb coefficient (0 = frictionless)
  /// Slip speed (m/s) below which friction acts as a spring (ε = this·h).
  double static_slip_speed = 1e-3;
};

/// "<object>/shape": the world frame giving a dynamic object's moving shape for a step (header).
std::string moving_shape_frame_name(const std::string& object);
/// A dynamic object's shape in its body frame for this step: the moving shape
/// frame `f` (world, t + h) relative to the body's pose `body_t` at t when the
/// inputs give it, else `fixed`. Throws one line naming `term` and the frame
/// of `object` when it is not finite.
Isometry step_shape_in_frame(const WorldFrame* f, const Isometry& body_t, const Isometry& fixed,
                             const std::string& term, const std::string& object);

class SdfContactTerm : public EnergyTerm {
 public:
  /// `samples`: the body's contact points (e.g. skin_contact_samples());
  /// `field` in the object's shape frame, placed by pose · shape_in_frame
  /// where pose is the world frame `object` (static/kinematic) or, when
  /// `dynamic_object`, the configuration of the term's second bound body.
  SdfContactTerm(std::string object, PosedPoints samples, geometry::SdfPtr field, const Isometry& shape_in_frame,
                 bool dynamic_object, const SdfContactOptions& options = {});
  std::string name() const override { return "contact:" + object_; }
  /// Static or kinematic: `object`; dynamic: its moving shape's frame (optional).
  std::vector<std::string> input_frames() const override;
  bool in_nonlinearity_check() const override { return false; }  // a contact term (energy_term.hpp)
  std::unique_ptr<TermCache> make_cache() const override;
  void begin_step(const StepContext& ctx) const override;
  bool active(const StepContext& ctx) const override;
  double compute(const StepContext& ctx, const Configuration& q, VecRef* grad, MatRef* hess) const override;
  /// "force" (3, N: what the object exerts on the body, world; normal and
  /// friction), "friction_force" (3, N, its friction part), "active_samples"
  /// (1: samples with φ < 0) and "max_penetration" (1, m) at the final q;
  /// while any sample is in contact also "contact_point" (3, m, world: the
  /// active samples' mean weighted by their normal force k|φ|).
  std::vector<TermQuantity> report(const StepContext& ctx, const Configuration& q) const override;

  const PosedPoints& samples() const { return samples_; }
  const SdfContactOptions& options() const { return options_; }
  const std::string& object() const { return object_; }
  bool dynamic_object() const { return dynamic_; }
  /// The field's world pose (step frame) for this context: from the frame or the object's iterate.
  Isometry field_pose(const StepContext& ctx) const;
  /// Candidate samples of the current step (after begin_step).
  const std::vector<int>& candidates(const StepContext& ctx) const;

 private:
  /// Friction potential of sample p at x (header comment), y = where the object
  /// carries the touched point; adds its gradient/Hessian.
  double friction(const StepContext& ctx, const Configuration& q, int p, const Vec3& x, double lambda, const Vec3& n,
                  const Vec3& y, double mu, double eps, VecRef* grad, MatRef* hess) const;
  /// For a potential of r = x_p(q) − y(q_object) (sample p; y the object's
  /// point, `ob` its 6 DoFs or −1): adds Jᵀg and JᵀHJ, J = ∂r/∂δ, to the
  /// body's columns (layout L) and the object's, given g = ∂E/∂r and H ≈ ∂²E/∂r².
  void add_point_derivatives(const Configuration& q, const DofLayout& L, int p, const Vec3& g, const Mat3& H, int ob,
                             const Vec3& y, VecRef* grad, MatRef* hess) const;
  struct Cluster {
    int bone = 0;
    Vec3 center = Vec3::Zero();  ///< unposed, m
    double radius = 0;           ///< m, slack included
    std::vector<int> samples;
  };
  std::string object_;
  PosedPoints samples_;
  geometry::SdfPtr field_;
  Isometry shape_in_frame_;
  bool dynamic_ = false;
  SdfContactOptions options_;
  std::vector<Cluster> clusters_;
};

/// The skin vertices of `avatar` to use as contact samples: every vertex
/// (spacing ≤ 0), or one vertex per cubic cell of `spacing` m in the unposed
/// space (the one nearest the cell's centre), so that density is uniform.
/// Each sample's basis row keeps its `max_handles` strongest handles (≤ 0:
/// all; PosedPoints::with_truncated_rows): a sample's Gauss–Newton block
/// costs (6 n_bones + 3 n_handles)², and the depth-blended basis gives skin
/// points up to ~60 handles with weights down to 1e-4. Default 8: on the
/// default avatar the largest weight dropped is reported by `max_dropped`.
PosedPoints skin_contact_samples(const Avatar& avatar, double spacing = 0.0, int max_handles = 8,
                                 double* max_dropped = nullptr);

}  // namespace sflsh
