#pragma once
// Full-FEM reference solver (issue 4, "the reference"): the ground truth the
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
// Rigid obstacles (issue 10; the reduced model's SdfContactTerm, sdf_contact.hpp):
// every skin vertex v is a contact sample embedded in its tet (surface_tet,
// surface_bary), x_v(u) = Σ_j w_vj G_j (x̄_v + Σ_c b_vc u_{n_c}) with the
// surface skinning weights w_vj, so it matches PosedPoints::at_surface when
// the reduced basis is complete. Each obstacle adds
//   E_o = Σ_v ½ k_o min(φ_o(T_o⁻¹ x_v), 0)²
// with gradient k φ b_c A_vᵀ ∇φ on node n_c (A_v = Σ_j w_vj R_j, ∇φ world) and
// the Gauss–Newton Hessian k b_c b_d A_vᵀ ∇φ ∇φᵀ A_v (PSD); the four nodes of a
// sample's tet are already coupled by the elastic pattern, so the sparsity
// pattern is unchanged. Samples outside an obstacle's bounding box are skipped
// (exactly: φ ≥ 0 there).
#include <memory>
#include <string>
#include <vector>

#include <Eigen/SparseCore>

#include "sflsh/asset/avatar.hpp"
#include "sflsh/fem/tet_operators.hpp"
#include "sflsh/geometry/sdf.hpp"
#include "sflsh/sim/configuration.hpp"
#include "sflsh/sim/material.hpp"
#include "sflsh/sim/posed_points.hpp"

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
  std::string name;          ///< for reports
  geometry::SdfPtr field;    ///< signed distance in the obstacle's local frame (non-null)
  double stiffness = 2.0e4;  ///< k, N/m per skin sample (SdfContactOptions' default)
};

/// One obstacle's contact at the end of a step.
struct FullFemContact {
  std::string name;
  Vec3 force = Vec3::Zero();   ///< N, world: what the obstacle exerts on the body, Σ_v −k φ_v ∇φ_v
  int active_samples = 0;      ///< skin samples with φ < 0
  double max_penetration = 0;  ///< m, max over samples of −φ (0 without contact)
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
  /// Adds a rigid obstacle acting on every skin vertex; returns its index
  /// (the position of its pose in step's `obstacle_poses`).
  int add_obstacle(FullFemObstacle obstacle);
  int num_obstacles() const { return int(obstacles_.size()); }
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
  /// #V by 3 world positions of the skin samples at nodal displacement u
  /// (no pose blend shapes: the points the contact acts on) at the current bones.
  Points skin_points(const Points& u) const;

 private:
  struct Cholmod;
  Points world_nodes(const Points& u, const std::vector<Isometry>& bones) const;
  double evaluate(const Points& u, VecX* grad, bool hessian);
  double evaluate_contact(const Points& u, VecX* grad, bool hessian, std::vector<FullFemContact>* report) const;
  Vec3 skin_point(int v, const Points& u) const;

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
  mutable double ms_contact_ = 0;
};

}  // namespace sflsh
