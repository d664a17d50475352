#pragma once
// Full-FEM reference solver ("the reference"): the ground truth the
// reduced simulator is measured against. Same tet mesh, material and skinning as
// the reduced model, but nodal DoFs:
//   u_n ∈ R³ (unposed space) for every Simulated node; Bone/Skinned nodes u = 0.
//   x_n(u) = Σ_j w_nj G_j (x̄_n + u_n)         (bones prescribed by the motion)
//   E(u) = Σ_n m_n/(2h²)|x_n − x*_n|² + Σ_e V_e Ψ(F_e) − Σ_n m_n g·x_n,
// lumped masses m_n = Σ_{e∋n} ρ_e V_e / 4, x*_n = 2 x_n(t) − x_n(t−h) (backward
// Euler, Gast et al. 2015), linear tets (constant F_e = I + Σ_c u_c ∇N_cᵀ),
// per-tet 12x12 Hessians with PSD-projected ∂²Ψ/∂F². Newton iterated to
// convergence with a backtracking line search; sparse supernodal Cholesky
// (CHOLMOD), symbolic analysis once, numeric factorization per iteration.
//
// Rigid obstacles (DESIGN.md §7; skin_face_samples.hpp): contact is a
// pressure on the skin's area, sampled over the skin's faces, so the reference
// force does not depend on the mesh (a per-vertex load has no continuum limit:
// a small probe touching one vertex gets a one-node force). Obstacle o with
// pressure stiffness κ_o (N/m³) and sample spacing s_o adds
//   E_o = Σ_s ½ κ_o a_s min(φ_o(T_o⁻¹ x_s), 0)²,   x_s = Σ_i λ_si x_{v_i}(u),
// over the samples s of the skin faces (n² sub-triangle centroids, weight a_s =
// rest area / n², barycentric λ_s on the face's vertices v_0..v_2), where each
// skin vertex is embedded in its tet (surface_tet, surface_bary) and skinned:
// x_v(u) = Σ_j w_vj G_j (x̄_v + Σ_c b_vc u_{n_c}) (surface weights w_vj), so it
// matches PosedPoints::at_surface when the reduced basis is complete. With
// J_s = ∂x_s/∂u = Σ_i λ_si b_{v_i c} A_{v_i} on node n_c of v_i's tet
// (A_v = Σ_j w_vj R_j) the gradient is κ a_s φ J_sᵀ ∇φ (exact) and the Hessian
// Gauss–Newton κ a_s J_sᵀ ∇φ ∇φᵀ J_s (PSD). J_s spans the up to 12 nodes of
// the face's three tets, which the elastic pattern does not couple: the first
// add_obstacle extends the sparsity pattern with every skin face's node
// couplings (not the constructor, so scenes without obstacles keep their
// pattern, ordering and results bit for bit).
// Broad phase per evaluation: a face whose three current skin points' box
// misses the obstacle's world box is skipped (exact: samples lie in the
// triangle, φ ≥ 0 outside the box); for unbounded fields (planes) a face is
// skipped when φ at one of its vertices exceeds its longest current edge
// (exact for a 1-Lipschitz φ: every sample is within that edge of each vertex).
// A candidate face's samples (per obstacle spacing) and its Hessian slots are
// made on first use and cached. Per face, the samples' derivatives are summed
// over the three vertices' world positions first (a 9-vector and a 9x9
// matrix: Σ_s w_s λ_i λ_j ∇φ ∇φᵀ), then mapped to the nodes once, so a
// sample costs O(1), not O(12²).
#include <array>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

#include <Eigen/SparseCore>

#include "sflsh/asset/avatar.hpp"
#include "sflsh/fem/tet_operators.hpp"
#include "sflsh/geometry/sdf.hpp"
#include "sflsh/sim/configuration.hpp"
#include "sflsh/sim/material.hpp"
#include "sflsh/sim/posed_points.hpp"
#include "sflsh/sim/skin_face_samples.hpp"

namespace sflsh {

struct FullFemOptions {
  double h = 1.0 / 60.0;                 ///< time step (s)
  Vec3 gravity = Vec3(0, -9.81, 0);      ///< m/s², world
  int max_iterations = 50;               ///< Newton iterations per step at most
  /// Converged when ‖∂E/∂u‖ ≤ gradient_tolerance · (‖∂E/∂u‖ at the start of the
  /// step + 1e-12 N) or the Newton step's largest nodal change ≤ step_tolerance.
  double gradient_tolerance = 1e-10;
  double step_tolerance = 1e-13;         ///< m
  bool line_search = true;               ///< Armijo backtracking on E (halving)
};

/// A rigid obstacle of the full-FEM reference; its pose is given per step (FullFem::step).
struct FullFemObstacle {
  std::string name;        ///< for reports and errors
  geometry::SdfPtr field;  ///< signed distance in the obstacle's local frame (non-null)
  double pressure_stiffness = kDefaultPressureStiffness;  ///< κ, N/m³: contact pressure per metre of penetration
  double spacing = kDefaultContactSpacing;  ///< m, sample spacing on the skin's faces (skin_face_samples.hpp)
};

/// A skin point tied to a tool point over one step (sim/energies/anchor.hpp's
/// energy): E = ½ k |x_v − a|² + ½ (c/h) |(x_v − x_v,t) − (a − a_t)|², x_v the
/// skin vertex (embedded in its tet and skinned, as the contact samples' points).
struct FullFemAnchor {
  int vertex = 0;                   ///< skin vertex (row of Avatar::surface_rest)
  Vec3 target = Vec3::Zero();       ///< a, m, world: the tool point at t + h
  Vec3 target_prev = Vec3::Zero();  ///< a_t, m, world: the tool point at t
  double hardness = 1.0e3;          ///< k, N/m (> 0)
  double damping = 1.0;             ///< c, N·s/m (>= 0)
};

/// One obstacle's contact at the end of a step.
struct FullFemContact {
  std::string name;
  Vec3 force = Vec3::Zero();   ///< N, world: what the obstacle exerts on the body, Σ_s −κ a_s φ_s ∇φ_s
  int active_samples = 0;      ///< skin face samples with φ < 0
  double max_penetration = 0;  ///< m, max over samples of −φ (0 without contact)
  double contact_area = 0;     ///< m², Σ a_s over the active samples (rest area)
};

struct FullFemReport {
  int iterations = 0;          ///< Newton iterations taken
  int projected_iterations = 0;  ///< of which the exact Hessian was indefinite (PSD element majorizers used)
  bool converged = false;
  double grad_norm_initial = 0, grad_norm = 0;  ///< N
  double energy = 0;           ///< J, at the end
  double ms_total = 0, ms_factorize = 0;
  double ms_contact = 0;       ///< time evaluating the obstacles' penalties (all evaluations)
  std::vector<FullFemContact> contacts;  ///< per obstacle, in add_obstacle order, at the final u
  /// N, world: what each anchor (set_anchors, in order) exerts on the body at
  /// the final u, −∂E/∂x_v; the tool feels the opposite. anchor_force: their sum.
  std::vector<Vec3> anchor_forces;
  Vec3 anchor_force = Vec3::Zero();
};

class FullFem {
 public:
  /// Precomputes masses, shape gradients and the sparsity pattern; rest state at
  /// identity bones (call reset for another start).
  explicit FullFem(std::shared_ptr<const Avatar> avatar, FullFemOptions options = {});
  ~FullFem();
  FullFem(const FullFem&) = delete;
  FullFem& operator=(const FullFem&) = delete;

  /// u = 0, zero velocity, at `bones` (24 world transforms), time 0.
  void reset(const std::vector<Isometry>& bones);
  /// Adds a rigid obstacle acting on the skin's faces (header comment); returns
  /// its index (the position of its pose in step's `obstacle_poses`). Throws one
  /// line naming the obstacle for a null field, κ or spacing not finite and > 0.
  int add_obstacle(FullFemObstacle obstacle);
  int num_obstacles() const { return int(obstacles_.size()); }
  /// The anchors of the next steps (FullFemAnchor; none by default), until
  /// set again. Throws one line naming the anchor for a vertex out of range, a
  /// target not finite, k not finite and > 0 or c not finite and >= 0.
  void set_anchors(std::vector<FullFemAnchor> anchors);
  int num_anchors() const { return int(anchors_.size()); }
  /// One backward-Euler step to t + h with the bones prescribed at `bones_next`
  /// and each obstacle's field placed at `obstacle_poses[i]` (local → world at
  /// t + h; one per add_obstacle, may be empty without obstacles).
  FullFemReport step(const std::vector<Isometry>& bones_next, const std::vector<Isometry>& obstacle_poses = {});

  double time() const { return time_; }
  /// Free DoFs (3 × #Simulated nodes).
  int num_dofs() const { return int(free_node_.size()) * 3; }
  /// #N by 3 nodal soft displacement (m, unposed; 0 at Bone/Skinned nodes).
  const Points& displacement() const { return u_; }
  /// #V by 3 posed surface through the surface embedding, pose blend shapes included (m, world).
  Points posed_surface() const;
  /// #V by 3 soft displacement of the surface vertices (m, unposed).
  Points soft_displacement() const;
  /// Total energy at nodal displacement u (#N by 3) for the current step
  /// (valid during/after step(); +inf if an element is inverted).
  double energy(const Points& u) const;
  /// The same with the gradient over the free DoFs (3 × #Simulated, node order
  /// of the Simulated nodes; N) and the symmetric Hessian Newton factorizes
  /// (exact elastic and inertia blocks, Gauss–Newton contact; N/m) when non-null.
  double energy(const Points& u, VecX* gradient, Eigen::SparseMatrix<double>* hessian) const;
  /// #V by 3 world positions of the skin vertices at nodal displacement u (no
  /// pose blend shapes: the points whose faces carry the contact samples) at the current bones.
  Points skin_points(const Points& u) const;

 private:
  struct Cholmod;
  Points world_nodes(const Points& u, const std::vector<Isometry>& bones) const;
  double evaluate(const Points& u, VecX* grad, bool hessian);
  double evaluate_contact(const Points& u, VecX* grad, bool hessian, std::vector<FullFemContact>* report) const;
  /// The anchors' energy; gradient, Hessian (exact: x_v is affine in u) and
  /// each anchor's force on the body when asked.
  double evaluate_anchors(const Points& u, VecX* grad, bool hessian, std::vector<Vec3>* forces) const;
  Vec3 skin_point(int v, const Points& u) const;
  /// Lower-CSC pattern of the Hessian (elastic + inertia; with the skin faces'
  /// node couplings when `couple_skin_faces`) and the tet / node slot tables.
  void build_pattern(bool couple_skin_faces);
  /// A skin face's free nodes (of its three tets) and the lower-CSC value slot
  /// of every entry of its 3m by 3m block (row-major, −1 above the diagonal).
  struct FaceNodes {
    std::vector<int> nodes;               // m free nodes
    std::array<std::array<int, 4>, 3> local;  // per face vertex and tet corner: index into nodes or −1
    std::vector<int> slots;               // 9 m²
  };
  const FaceNodes& face_nodes(int f) const;
  const std::vector<SkinFaceSample>& face_samples(int obstacle, int f) const;

  std::shared_ptr<const Avatar> avatar_;
  FullFemOptions options_;
  std::vector<int> free_node_;       // free index → node
  std::vector<int> node_free_;       // node → free index or −1
  VecX mass_;                        // #N lumped masses (kg)
  VecX volume_;                      // #T
  std::vector<fem::TetGradient> grads_;  // #T shape-function gradients
  std::vector<MaterialPoint> materials_;
  bool project_hessian_ = false;  // element Hessians: exact, or PSD majorizers  // #T, region material in the tet's frame
  std::vector<int> tet_slot_;        // #T·144: value index in the lower CSC or −1
  std::vector<int> node_slot_;       // #free·9: value index of the diagonal inertia block or −1
  std::unique_ptr<Cholmod> chol_;
  // State.
  std::vector<Isometry> bones_;      // at t (and at t + h during a step)
  Points u_;                         // #N by 3
  Points x_now_, x_prev_, x_pred_;   // #N by 3 world nodes at t, t − h, prediction
  std::vector<Mat3> A_;              // per node Σ_j w_nj R_j at the step's bones
  double time_ = 0;
  PosedPoints surface_;
  // Contact.
  std::vector<FullFemObstacle> obstacles_;
  std::vector<Isometry> obstacle_poses_;  // at t + h during a step
  std::vector<Mat3> skin_A_;              // per skin vertex Σ_j w_vj R_j at the step's bones
  bool skin_faces_coupled_ = false;       // pattern holds the skin faces' node couplings
  mutable std::unordered_map<int, FaceNodes> face_nodes_;  // per candidate face, made on first use
  mutable std::vector<std::unordered_map<int, std::vector<SkinFaceSample>>> face_samples_;  // per obstacle, per face
  mutable double ms_contact_ = 0;
  // Anchors.
  std::vector<FullFemAnchor> anchors_;
  std::vector<Vec3> anchor_start_;  // x_v,t per anchor (world, at the step's start)
};

}  // namespace sflsh
