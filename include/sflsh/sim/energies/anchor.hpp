#pragma once
// Anchors: flesh points tied to points of a tool (AMBF Alg. 3/4),
// as a term of the backward-Euler objective instead of explicit forces, so a
// stiff grasp stays stable. Flesh point p is embedded in its tet (a row of a
// PosedPoints set: x_p(q) follows the bones and the soft DoFs z); it is tied
// to the tool point a_p by a spring of hardness k (N/m) and a damper c (N·s/m):
//   E = Σ_p ½ k |x_p(q) − a_p|² + ½ (c/h) |(x_p(q) − x_p,t) − (a_p − a_p,t)|²,
// x_p,t = x_p(q_t), a_p,t = the tool point at time t. The second sum is the
// backward-Euler (Rayleigh) potential of the damper: its gradient is
// c·(v_x − v_a) with v = displacement over the step / h, the damping force of
// the relative velocity at t + h. Gradient exact; Hessian Gauss–Newton
// (k + c/h) Σ_p D_pᵀ D_p with D_p = ∂(x_p − a_p)/∂δ (PSD; it drops the
// curvature of x_p(q) in the bones' rotations, (x − a)·∂²x/∂δ²).
//
// The tool is
//   * kinematic: the term is bound to the body alone; a_p is given at t + h;
//   * dynamic: a rigid-object body of the model (model.hpp), bound second;
//     a_p = G_tool(q) · o_p with o_p the anchor's offset in the tool's body
//     frame, and the term fills the tool's 6 DoFs (∂a/∂ξ = [−[a]×, I]), so
//     the forces on flesh and tool are equal and opposite.
//
// Which anchors exist is per-step data (grasping and releasing does not
// rebuild the model): it travels in StepInputs::anchors, the term's anchor
// set (AnchorSetId: the model registers the set named after the term's
// `tool`), one AnchorPoint per anchor (the term takes them by increasing
// point, the last one given for a point):
//   * kinematic tool: its position is the tool point a_p at t + h (world),
//     its velocity the point's velocity (m/s): a_p,t = a_p − h v;
//   * dynamic tool: its position is the tool point at time t, G_t · o_p
//     (world); its velocity is ignored; o_p = G_t⁻¹ · position.
// anchor_points() writes them from the tool's pose and twist and the
// anchors' offsets in the tool frame. The term reads them as given (world)
// and takes them into the step frame itself (StepContext::frame_origin).
#include <string>
#include <vector>

#include "sflsh/sim/energy_term.hpp"
#include "sflsh/sim/posed_points.hpp"

namespace sflsh {

/// One anchor: row `point` of the term's flesh points tied to `offset` (m) in the tool's frame.
struct Anchor {
  int point = 0;
  Vec3 offset = Vec3::Zero();
};

/// Sets `points` to one AnchorPoint per anchor, in order (header comment).
/// Kinematic tool: `tool_frame` is the tool's pose and twist at t + h (world;
/// ω rad/s, v m/s of the frame's origin); dynamic tool: its body pose G_t at
/// time t, twist ignored.
void anchor_points(const WorldFrame& tool_frame, const std::vector<Anchor>& anchors, bool dynamic_tool,
                   std::vector<AnchorPoint>& points);

struct AnchorOptions {
  double hardness = 1.0e3;  ///< k, N/m per anchor (> 0)
  double damping = 1.0;     ///< c, N·s/m per anchor (≥ 0)
};

class AnchorTerm : public EnergyTerm {
 public:
  /// `points`: the flesh points anchors may use (e.g. PosedPoints::at_surface:
  /// anchors then name skin vertices); `tool`: the tool's name (also the name
  /// of the term's anchor set); `dynamic_tool`: the tool is the term's second
  /// bound body. Throws on a non-positive hardness or negative damping.
  AnchorTerm(std::string tool, PosedPoints points, bool dynamic_tool, const AnchorOptions& options = {});
  std::string name() const override { return "anchor:" + tool_; }
  std::string input_anchor_set() const override { return tool_; }
  std::unique_ptr<TermCache> make_cache() const override;
  /// Reads the step's anchors from ctx.anchors (none: inactive; a point
  /// index out of range or a non-finite point throws naming the term).
  void begin_step(const StepContext& ctx) const override;
  bool active(const StepContext& ctx) const override;
  double compute(const StepContext& ctx, const Configuration& q, VecRef* grad, MatRef* hess) const override;
  /// At q: "force" (3, N, world: what the tool exerts on the flesh, summed),
  /// "anchor_forces" (3·#anchors, N, per anchor in the order of
  /// "anchor_points"), "anchor_points" (#anchors, point indices),
  /// "max_stretch" (1, m: the largest |x_p − a_p|).
  std::vector<TermQuantity> report(const StepContext& ctx, const Configuration& q) const override;

  const PosedPoints& points() const { return points_; }
  const std::string& tool() const { return tool_; }
  bool dynamic_tool() const { return dynamic_; }
  const AnchorOptions& options() const { return options_; }
  /// The anchors of the current step (after begin_step): point indices.
  std::vector<int> anchored_points(const StepContext& ctx) const;
  /// Tool point a_p (m, step frame) of the i-th anchor of the step at the current iterate.
  Vec3 tool_point(const StepContext& ctx, int i) const;

 private:
  std::string tool_;
  PosedPoints points_;
  bool dynamic_ = false;
  AnchorOptions options_;
};

}  // namespace sflsh
