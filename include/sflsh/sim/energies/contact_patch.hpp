#pragma once
// Rigid ↔ flesh contact that dents (DESIGN.md §7): contact sampled over the
// skin's faces with a pressure stiffness (skin_face_samples.hpp), and a
// full-space patch under the contact.
//
// The reduced basis is global and smooth: a 2 cm probe needs a dent a few
// centimetres wide, which the handles cannot form, so a pure subspace carries
// the load through penetration and its force is several times the full FEM's.
// Here the tet nodes within `patch_radius` (unposed) of the skin near the
// object get their own displacement δu on top of the subspace,
//   u_n = W_n z + δu_n   (unposed, m),   δu = 0 outside the patch,
// and the step's energy gains the exact change that δu brings:
//   Φ(q, δu) = Σ_{t ∈ patch tets} V_t [Ψ(F_t(Wz + δu)) − Ψ_t^sub(F_t(Wz))]       (elasticity)
//            + Σ_{n ∈ patch} m_n/(2h²) |r_n + e_n|² − m_n g·d_n
//            − Σ_{s ∈ S_p} m_s/(2h²) |r_s|²                                          (inertia, gravity)
//            + Σ_s ½ κ a_s min(φ(x_s), 0)²                                          (contact)
// with d_n = A_n δu_n the node's world offset (A_n = Σ_j w_nj R_j), r_n = x_n(q)
// − x*_n the subspace node's inertial residual, e_n = d_n − (2 d_n(t) − d_n(t−h))
// (δu carries its own velocity while the patch persists), and x_s = Σ_i λ_i
// (x_{v_i}(q) + A_{v_i} Σ_c b_{v_i c} δu_{n_c}) a face sample over the skin
// vertices v_i embedded in their tets (surface_tet, surface_bary), and S_p
// the inertia cubature's samples whose main node is a patch node (r_s their
// inertial residual). The patch region is integrated exactly in place of what
// the subspace's terms hold of it; where they hold it exactly (the limit
// below) nothing but the contact remains without δu: the patch only refines.
//
// What the patch subtracts: the inertia samples S_p (their whole share of the
// subspace's kinetic term), and Ψ_t^sub, tet t's share of the quadratic part
// of the body's elastic term (elastic.hpp): the exact small-strain quadratic,
// with mean dilatation only its own share of it (α H₂ + (1 − α) P H₂ P, the
// rest averaged over the tet's cell and left in the subspace). Subtracting
// the tet's exact Ψ instead, as if the subspace held it, gives local volume
// changes inside a patch a negative stiffness of about the bulk modulus (the
// subspace holds α = 0.2 of it): a 2 cm probe pressed 2 cm into the belly ran
// away within a second (the step's Hessian indefinite beyond any diagonal
// shift). The same holds for inertia: subtracting the nodes' exact |r_n|²
// where the mass cubature holds less made a 1 cm probe yanked through the
// belly at 500 Hz blow the flesh up to 78 kJ of elastic energy.
//
// The cubature's nonlinear remainder Ψ − Ψ₂ (and compression guard) at the
// subspace's state stays: it is what keeps the subspace's own state sane
// under a patch. Cancelled at the samples inside the patch, it left the
// handles there nearly free (δu makes up for W z inside the patch), and a
// football at 6 m/s, stepped at 1/120 s, drove z to crush a sample the patch
// hid from the step: 0.76 MJ held by the subspace and cancelled by the patch,
// until the patch released it (32 kN, 82 rejected steps). Kept, it costs
// nothing where W z is small-strain (the remainder is cubic in the strain,
// and the minimum over z and δu puts a dent into δu) and rises steeply where
// the subspace would crush or overstretch a sample.
//
// Condensation (Teng et al. 2015, "Subspace condensation"): the term's energy
// is E(q) = min_δu Φ(q, δu), the patch minimized out at every evaluation
// (Newton on δu with q fixed: a small sparse system, factored by a sparse
// Cholesky in 3x3 node blocks whose ordering is shared by the patch's factors
// and kept while its pattern holds; a few iterations).
// Then ∂E/∂q = ∂Φ/∂q at the minimizer (envelope theorem) and the Hessian is
// the Schur complement Φ_qq − Φ_qp Φ_pp⁻¹ Φ_pq over the rows the patch
// touches, so the global step stays one Newton step over bones and handles.
// Approximations, all in the Hessian only: Gauss–Newton for the contact, the
// element Hessians PSD-projected, the change of the elastic Hessian in the patch (K(Wz + δu) − K^sub(Wz)) reduced
// to its small-strain part (the bulk share mean dilatation leaves out, rank
// one per tet), the cross block Φ_zp taken at the subspace's state (Wᵀ K^sub)
// with a guard that keeps the complement below what the subspace holds
// (compute), and A_n held at the iterate's bones (δu's rotation with the
// bones is not differentiated).
//
// Trials: δu is minimized at each Newton iteration's start q0 only. The
// iteration's trials q0 ⊕ Δ (the line search's, and the step's end when it
// is accepted) take the back-substitution of the bordered system,
// δu0 − Φ_pp⁻¹ (Φ_p + Φ_pq Δ), with Φ_pp itself and the dented tets' own
// cross block Wᵀ K1 (not the complement's guarded blocks): first-order
// exact, so a trial's energy is that of (q, δu) one Newton step from the
// minimum, and the next iteration or step minimizes again from there. The
// minimizer instead where the back-substitution would crush a patch tet.
// (Minimized at every trial, each step paid for a second inner Newton.)
//
// Inner minimization: Newton on δu until its step moves no node by more than
// inner_tolerance (µm against mm dents). What is left, Φ_pp⁻¹ Φ_p, enters the
// step through the bordered system's right-hand side: the iteration's
// gradient is Φ_q − Φ_qp Φ_pp⁻¹ Φ_p, the gradient of the energy its trials
// see. The step's start extrapolates δu from its last two steps and takes
// back what the other DoFs' move over the last step contributed to it
// (PatchHistory::du_back, carried in checkpoints); when every patch node has
// such a history, that start is evaluated with the q derivatives the
// iteration needs and, already within the tolerance (most steps of a probe
// or a slow press), it is used as is: one evaluation and one factorization
// of Φ_pp per Newton iteration.
//
// Limit: with the patch covering every Simulated node, the elastic cubature
// exact per tet and the inertia lumped at the nodes, E(q) is the full FEM's
// energy of u = Wz + δu minimized over δu, plus the remainder at W z, which
// has no gradient and no Hessian at rest (cubic) and stays small while δu
// takes the dent: the step is the full-FEM step (to 1e-6 of the dent,
// contact_patch_test.cpp).
//
// Life of a patch: begin_step selects the candidate faces (a vertex within
// reach of the object at time t) and the patch nodes (Simulated nodes within
// patch_radius of a near vertex, plus every node whose δu is still above
// release_displacement). The displacement at t + h is the one at the
// step's final q (its last trial's, above), fixed when the integrator asks
// for the report. When no
// skin is near the object (and no anchor holds), the patch is released: δu
// is no longer minimized but prescribed, decaying as exp(−t/release_time)
// (δu(t + h) = e^(−h/τ) δu(t)), and a node leaves once its δu is below
// release_displacement. Out of contact the minimizer is not zero (the
// full space relaxes what the subspace holds of the patch's tets), so a patch
// kept until its dent relaxes never leaves: a ball that bounced off the
// belly kept a 196-node patch, 8 Newton iterations on δu a step, for ever.
// The decay releases it over a few time constants without a pop, and the
// term costs one evaluation (no inner Newton, no Schur complement) meanwhile.
//
// Friction (Coulomb, lagged per step; Li et al. 2020, "Incremental Potential
// Contact" §5, as sdf_contact.hpp): a face sample touching at time t, at
// x_s(t) with the patch's δu(t), gets λ_s = κ a_s max(0, −φ(x_s(t))) and the
// normal n_s there, and Φ gains μ λ_s f0(|(I − n_s n_sᵀ)(x_s − y_s)|), y_s
// where the object carries the touched point by the iterate; its gradient and
// PSD Hessian enter like the pressure's, through the face's vertices (both
// δu and q), so the patch dents and shears under a dragged or resting object.
// A sample feels friction one step after it touches.
//
// Objects: static, kinematic (a world frame of the step inputs) or
// dynamic (a rigid body of the model: its 6 DoFs join the condensed system),
// whose shape may move on it (a jaw of a coupled gripper: the frame
// "<object>/shape" gives its pose for the step, as for sdf_contact.hpp).
//
// One patch per term: the patches of two terms (two objects, a gripper's
// jaws and its anchors) do not merge. Where they overlap, each holds its own
// δu and each adds the exact energy of the shared tets less the subspace's:
// the tissue there counts about twice (too stiff, not unstable). A tool's
// shape and anchors share one term, hence one patch.
#include <memory>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include "sflsh/geometry/sdf.hpp"
#include "sflsh/sim/energies/anchor.hpp"
#include "sflsh/sim/energies/sdf_contact.hpp"
#include "sflsh/sim/energy_term.hpp"
#include "sflsh/sim/material.hpp"
#include "sflsh/sim/posed_points.hpp"
#include "sflsh/sim/skin_face_samples.hpp"
#include "sflsh/sim/step_report.hpp"

namespace sflsh {

namespace contact_patch_detail {
struct PatchHistory;  // contact_patch_cache.hpp
}

struct ContactPatchOptions {
  double pressure_stiffness = kDefaultPressureStiffness;  ///< κ, N/m³
  double spacing = kDefaultContactSpacing;                ///< m, face sample spacing
  /// The full-space patch (false: contact on the subspace alone, sampled the same way).
  bool patch = true;
  /// m (unposed, > 0): Simulated nodes this close to a skin vertex near the
  /// object get a full-space displacement (at least; see below).
  double patch_radius = 0.04;
  /// A broad contact deforms the tissue deeper than a small one (the stress
  /// under a pressed disc of radius a falls to about 40 % of the surface's at
  /// depth 1.5 a): the radius grows to this many times the contact's radius a
  /// when that is larger than patch_radius. a = 2 σ₂, σ₂² the middle
  /// eigenvalue of the near skin vertices' covariance (unposed): the radius of
  /// a disc, the half-width of a strip (an edge pressed along a limb). 0: the
  /// fixed patch_radius. A 16 cm sphere pressed 3 cm into the belly (a ≈ 6 cm)
  /// gets 45 % too much force with a 4 cm patch, within 1 % with 8 cm.
  double patch_radius_per_contact_radius = 1.5;
  /// Nodes selected around the contact at most (its system is dense: cost ~
  /// nodes³): beyond, the nodes nearest the deepest contact are kept (a broad
  /// press). Nodes still displaced from earlier steps stay on top of these
  /// until released (a moving contact's patch can hold more).
  int max_patch_nodes = 120;
  /// m: a skin vertex is near the object when φ at time t is below this plus
  /// its motion and the object's over the step.
  double margin = 0.005;
  int max_inner_iterations = 30;  ///< Newton iterations on δu per evaluation
  /// m: they end when the Newton step s moves no patch node by more than this
  /// (‖s‖∞). The step's bordered Newton system then takes the rest of Φ's
  /// gradient in δu along (its right-hand side holds it), so δu need not be
  /// converged further: a probe's 10 mm dent moves by a few µm per step.
  double inner_tolerance = 1e-5;
  double release_displacement = 1e-6;  ///< m: a node leaves the patch once |δu| is below this
  /// s (> 0): out of contact, δu decays with this time constant (header comment, "Life of a patch").
  double release_time = 0.02;
  int max_handles = 8;                 ///< basis row truncation of the skin vertices (sdf_contact.hpp)
  /// Coulomb μ (>= 0) between the skin and the object, lagged per step over
  /// the face samples as sdf_contact.hpp's friction (header comment, "Friction").
  double friction = 0.0;
  double static_slip_speed = 1e-3;  ///< m/s: slip below which friction is a spring (ε = this·h)
  /// The body's elastic term averages the volume change per cell
  /// (SoftTissueOptions::mean_dilatation): the patch subtracts what that term
  /// holds of each tet, so it must know (header comment, "What the patch subtracts").
  bool subspace_mean_dilatation = true;  // SoftTissueOptions' default
};

/// A grasping tool's anchors (anchor.hpp) held by a patch term:
/// the anchored skin vertices seed the patch like touching vertices, and
/// their springs join Φ at the vertices' full position (subspace plus patch):
///   Σ_p ½ k |x_p − a_p|² + ½ (k_d/h) |(x_p − x_p,t) − (a_p − a_p,t)|²,
/// x_p = x_p(q) + A_p Σ_c b_pc δu_c. A pinch lifts a tent a few centimetres
/// wide that the smooth subspace cannot form: on the subspace alone the
/// springs carry the lift through their stretch, and the tool's force is
/// several times the full FEM's. The tool is kinematic or, with the term's
/// dynamic object, a rigid body bound second; its anchor points come as
/// AnchorTerm takes them (a_p at t + h, or at t for a dynamic tool: a_p =
/// G_tool(q) o_p), and the tool gets the opposite force.
struct PatchAnchors {
  std::string set;        ///< the anchor set the step inputs give (EnergyTerm::input_anchor_set)
  AnchorOptions options;  ///< hardness k (N/m) and damping k_d (N·s/m) per anchor
};

class ContactPatchTerm : public EnergyTerm {
 public:
  /// `field` in the object's shape frame, placed by the world frame `object`
  /// of the step inputs times `shape_in_frame`. Throws on bad options (one line).
  /// The object is static or kinematic (a world frame of the step
  /// inputs, placed by `shape_in_frame`), or, when `dynamic_object`, a rigid
  /// body of the model bound second (its configuration's bone 0 times
  /// `shape_in_frame`, or the step's moving shape frame relative to the body
  /// at t when the inputs give it; equal and opposite forces, as sdf_contact.hpp).
  /// With `anchors` the term also holds the object's (a tool's) grasping
  /// tool's anchors (PatchAnchors); `field` may then be null (a tool without
  /// a shape: anchors only).
  ContactPatchTerm(std::string object, const Avatar& avatar, geometry::SdfPtr field, const Isometry& shape_in_frame,
                   bool dynamic_object, const ContactPatchOptions& options = {},
                   std::optional<PatchAnchors> anchors = std::nullopt);
  /// "contact:<object>", or "anchor:<set>" for anchors without a shape.
  std::string name() const override { return field_ ? "contact:" + object_ : "anchor:" + anchors_->set; }
  /// With a shape: the world frame `object` (static or kinematic), or a
  /// dynamic object's moving shape frame (optional, as SdfContactTerm's: a
  /// gripper's jaw on a coupled tool); without a shape none.
  std::vector<std::string> input_frames() const override {
    if (!field_) return {};
    return {dynamic_ ? moving_shape_frame_name(object_) : object_};
  }
  std::string input_anchor_set() const override { return anchors_ ? anchors_->set : ""; }
  bool in_nonlinearity_check() const override { return false; }  // a contact term (energy_term.hpp)
  std::unique_ptr<TermCache> make_cache() const override;
  void begin_step(const StepContext& ctx) const override;
  bool active(const StepContext& ctx) const override;
  double compute(const StepContext& ctx, const Configuration& q, VecRef* grad, MatRef* hess) const override;
  /// "force" (3, N, what the object exerts on the body, world; pressure and
  /// friction), "friction_force" (3, N, its friction part), "active_samples",
  /// "max_penetration" (m), "contact_area" (m²), "patch_nodes", "patch_radius" (m), "max_patch_displacement" (m),
  /// "patch_displacement" (4 per patch node: the node's index, then its δu, m, unposed),
  /// "contact_point" (3, m: the touching samples' mean weighted by their force; only in contact);
  /// with anchors also "anchor_forces", "anchor_points" and "max_stretch" as
  /// AnchorTerm (the vertices at their patched position), their forces in "force";
  /// also fixes the patch displacement of the step (header comment).
  std::vector<TermQuantity> report(const StepContext& ctx, const Configuration& q) const override;

  const ContactPatchOptions& options() const { return options_; }
  /// Patch nodes of the current step (after begin_step).
  std::vector<int> patch_nodes(const StepContext& ctx) const;

  struct Evaluation;  // one evaluation of Φ and its derivatives (contact_patch.cpp)

 private:
  struct EvaluationMode {
    bool q_derivatives = false;   ///< ∂Φ/∂q
    bool q_hessian = false;       ///< with q_derivatives: also Φ_qq, Φ_qp and K0_pp
    bool p_derivatives = true;    ///< ∂Φ/∂δu and Φ_pp
    bool project = true;          ///< PSD-projected element Hessians (else exact)
    bool subspace_energy = true;  ///< include −Σ V Ψ(F(Wz)) (constant in δu)
    /// Φ_pp is formed: asked for, or for the condensation of Φ_qq (a
    /// gradient-only evaluation, a trial's, leaves it out).
    bool pp_hessian() const { return p_derivatives || (q_derivatives && q_hessian); }
  };
  double evaluate_patch(const StepContext& ctx, const Configuration& q, const VecX& du, const EvaluationMode& mode,
                        Evaluation& out) const;
  // Its parts (contact_patch_evaluation.cpp), each adding to `out` and returning its energy:
  // the patch nodes' inertia and gravity less the inertia samples the subspace holds there,
  double add_patch_inertia(const StepContext& ctx, const Configuration& q, const VecX& du, const EvaluationMode& mode,
                           Evaluation& out) const;
  // the patch tets' elasticity less what the subspace's elastic term holds of them (+inf if one inverts),
  double add_patch_elasticity(const StepContext& ctx, const Configuration& q, const VecX& du,
                              const EvaluationMode& mode, Evaluation& out) const;
  // the contact over the candidate faces' samples,
  double add_patch_contact(const StepContext& ctx, const Configuration& q, const VecX& du, const EvaluationMode& mode,
                           Evaluation& out) const;
  // the anchors' springs and dampers (contact_patch_anchors.cpp).
  double add_patch_anchors(const StepContext& ctx, const Configuration& q, const VecX& du, const EvaluationMode& mode,
                           Evaluation& out) const;
  /// Reads the step's anchors into the cache; appends the anchored vertices
  /// to the seeds (their φ: minus the stretch at t, at least 1e-9 deep).
  void collect_anchors(const StepContext& ctx, TermCache& cache, std::vector<int>& seeds,
                       std::vector<double>& seed_phi) const;

  /// Minimizes Φ over δu at q (warm start: the step's prediction, then the last
  /// linearization's back-substitution); returns the minimizer.
  /// With `start`: a Newton iteration's start, whose evaluation (with q's
  /// derivatives) is in `*start` when `*at_start` (the warm start minimized Φ).
  VecX minimize_patch(const StepContext& ctx, const Configuration& q, Evaluation* start = nullptr,
                      bool* at_start = nullptr) const;
  /// δu at a Newton iteration's trial q: the bordered system's
  /// back-substitution from the iteration's start (linearized_patch), so
  /// that bones, handles and patch take one Newton step together; the
  /// minimizer where there is no linearization, q is its own, or the
  /// back-substitution would crush a patch tet.
  VecX step_patch(const StepContext& ctx, const Configuration& q) const;
  /// δu_lin − Φ_pp⁻¹ Φ_pq (q ⊖ q_lin), the last Hessian evaluation's linearization.
  VecX linearized_patch(const StepContext& ctx, const Configuration& q) const;
  /// q ⊖ q_from over the term's layout, with a dynamic object's object ⊖ object_from.
  VecX move_between(const StepContext& ctx, const Configuration& q, const Configuration& q_from,
                    const Configuration* object, const Configuration* object_from) const;
  /// Whether the cache's δu minimizes Φ at q (and the object's pose).
  bool patch_solved_at(const StepContext& ctx, const Configuration& q) const;
  /// The dynamic object's pose at the iterate (identity for a static or kinematic one).
  Isometry object_pose(const StepContext& ctx) const;
  /// Whether q and the object's pose are bit for bit `seen` and `object_seen`.
  bool at_configuration(const StepContext& ctx, const Configuration& q, const Configuration& seen,
                        const Isometry& object_seen) const;
  /// The constant Hessian of tet `t`'s share in the quadratic part of the
  /// body's elastic term, per unit volume (H2 the tet's small-strain Hessian):
  /// the stiffness the cross block Φ_zp takes for the tet.
  Mat9 subspace_quadratic_hessian(int t, const Mat9& H2) const;
  // begin_step's parts (contact_patch.cpp), each filling the term's cache:
  /// The skin vertices near the object at t (increasing) and their φ; places the field at t + h.
  void find_near_vertices(const StepContext& ctx, TermCache& cache, std::vector<int>& near,
                          std::vector<double>& near_phi) const;
  void collect_candidate_faces(TermCache& cache, const std::vector<int>& near) const;
  /// The candidate samples' friction at time t (x_s with the patch's δu(t), cache's du; header comment, "Friction").
  void prepare_friction(const StepContext& ctx, TermCache& cache, const Configuration& qt) const;
  void prepare_patch_tets(TermCache& cache) const;
  /// det F(W z + δu) of each patch tet (cache order).
  std::vector<double> patch_tet_determinants(const TermCache& cache, const VecX& z, const VecX& du) const;
  /// Keeps the patch's start admissible at the subspace's state z (time t),
  /// with the nodes' displacement at t (every tet's det F > 0):
  ///  - a node that `left` the patch this step (δu below
  ///    release_displacement) returns with its history to a tet that needs
  ///    its δu (one the subspace alone crushes);
  ///  - a new node in a tet the subspace inverts is left out while it does
  ///    (no δu starts it admissible: the subspace's elastic term samples few
  ///    tets, so an inverted tet it does not sample goes unnoticed until a
  ///    patch reaches it);
  ///  - a released patch decays by `decay` only while its tets keep a volume
  ///    ratio of kReleaseMinVolumeRatio; else it is minimized this step.
  void keep_start_admissible(TermCache& cache, const VecX& z,
                             const std::unordered_map<int, contact_patch_detail::PatchHistory>& left,
                             double decay) const;
  /// The bulk share of Φ_zz the patch tets add (cache's bulk_hessian), kept while they stay the same.
  void prepare_bulk_hessian(TermCache& cache) const;
  /// The rows of the term's system the q blocks can hold this step (cache's q_rows; at q).
  void collect_q_rows(const StepContext& ctx, TermCache& cache, const Configuration& q) const;
  /// Fills the cache's patch nodes around the seed vertices (φ of each seed; contact_patch.cpp).
  void select_patch_nodes(TermCache& cache, const std::vector<int>& seeds, const std::vector<double>& seed_phi) const;
  /// The dynamic object's 6 DoFs in the term's local system, or −1.
  int object_offset(const StepContext& ctx) const;

  std::string object_;
  const Avatar* avatar_;
  geometry::SdfPtr field_;
  Isometry shape_in_frame_;
  bool dynamic_ = false;
  ContactPatchOptions options_;
  std::optional<PatchAnchors> anchors_;
  PosedPoints vertices_;  // skin vertices (subspace), rows truncated
  PosedPoints nodes_;     // tet nodes (subspace)
  VecX node_mass_;        // lumped, kg
  std::vector<Eigen::Matrix<double, 4, 3>> grads_;  // per tet shape gradients
  VecX tet_volume_;
  VecXi dilatation_cell_;  // per tet (mean dilatation), else empty
  PosedPoints inertia_points_;     // the inertia cubature's samples
  VecX inertia_mass_;              // their masses, kg
  std::vector<int> sample_node_;   // their main node
  std::vector<MaterialPoint> materials_;
  std::vector<std::vector<int>> node_tets_;    // tets of each node
  std::vector<std::pair<double, int>> simulated_by_x_;  // (unposed x, node) of the Simulated nodes, increasing
  std::vector<std::vector<int>> vertex_faces_;  // skin faces of each vertex
  struct VertexCluster {
    int bone = 0;
    Vec3 center = Vec3::Zero();  // unposed, m
    double radius = 0;           // m, slack included
    std::vector<int> vertices;
  };
  std::vector<VertexCluster> clusters_;
};

/// #V by 3 soft displacement (m, unposed) that the patches of `report` add
/// to the skin vertices: each vertex takes its tet's nodes' δu (quantities
/// "patch_displacement" of every term of body `body`), barycentrically.
/// Zero where no patch is.
Points patch_surface_displacement(const Avatar& avatar, const StepReport& report, int body = 0);

}  // namespace sflsh
