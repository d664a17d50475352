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
#include <memory>
#include <vector>

#include "sflsh/asset/avatar.hpp"
#include "sflsh/fem/tet_operators.hpp"
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

struct FullFemReport {
  int iterations = 0;          ///< Newton iterations taken
  int projected_iterations = 0;  ///< of which the exact Hessian was indefinite (PSD element majorizers used)
  bool converged = false;
  double grad_norm_initial = 0, grad_norm = 0;  ///< N
  double energy = 0;           ///< J, at the end
  double ms_total = 0, ms_factorize = 0;
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
  /// One backward-Euler step to t + h with the bones prescribed at `bones_next`.
  FullFemReport step(const std::vector<Isometry>& bones_next);

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

 private:
  struct Cholmod;
  Points world_nodes(const Points& u, const std::vector<Isometry>& bones) const;
  double evaluate(const Points& u, VecX* grad, bool hessian);

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
};

}  // namespace sflsh
