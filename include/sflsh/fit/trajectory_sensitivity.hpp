#pragma once
// The simulated skin as a differentiable function of material parameters
// (seed §1: one Newton step of backward Euler per time step).
//
// The avatar runs with prescribed (kinematic) bones, as `sflsh simulate
// --bones kinematic` runs it: each step solves only the reduced soft DoFs z,
//   z_{t+1} = z_t + δ_t,   H δ_t = −g(z_t; z_t, z_{t−1}, p),
// with the model's own terms (inertia, elastic, gravity, damping) through
// sim::step, so the forward run is the simulator's to the bit. Forward
// sensitivities S_t = dz_t/dp (3K by #p) follow by differentiating that step,
// with the step's Hessian H (factored once per step, Cholesky):
//   H S_{t+1} = (A + (2/h²) J₁ᵀ M J₀ + c K) S_t − C − (1/h²) J₁ᵀ M J₋₁ S_{t−1}
//               − [∂K/∂p (z_{t+1} + c δ_t) + b]   (elastic parameters)
//               − K δ_t / h                       (damping β, c = β/h),
// J_i = ∂x/∂z of the inertia samples under the bones at t+1, t, t−1, M their
// masses, K the elastic stiffness at rest (= the damping's K₀), A, C and b from
// ElasticSensitivity (sim/elastic_sensitivity.hpp). S_0 = S_{−1} = 0 (the run
// starts undeformed). Surface vertices x_v = Σ_i w_vi G_i (x̄_v + U_v z + b_v)
// give dx_v/dp = (Σ_i w_vi R_i) U_v S_t.
//
// Steps the simulator shortened (z step caps, inadmissible energy) are still
// differentiated as the full Newton step (their count is reported).
#include <vector>

#include "sflsh/asset/avatar.hpp"
#include "sflsh/fit/fit_parameters.hpp"
#include "sflsh/sim/configuration.hpp"

namespace sflsh {

/// What drives a run: the time step and the prescribed bones.
struct BoneSequence {
  double h = 1.0 / 60.0;                      ///< s
  std::vector<Isometry> bones_before;         ///< 24 world transforms at t = −h (velocity at t = 0)
  std::vector<std::vector<Isometry>> bones;   ///< per step s = 0..N: 24 world transforms at t = s h
  double gravity_y = -9.81;                   ///< m/s², along world Y
  int num_steps() const { return int(bones.size()) - 1; }
};

/// The skin at chosen steps, and its derivative.
struct SurfaceRun {
  std::vector<Points> surface;  ///< per requested step: #Vsel by 3 world positions (m)
  std::vector<MatX> jacobian;   ///< per requested step: 3·#Vsel by #p, row 3i + c = ∂x_i[c]/∂p (when asked)
  int shortened_steps = 0;      ///< steps the simulator did not take in full (see header)
  double ms_simulate = 0, ms_sensitivity = 0;  ///< wall time of the forward run and of the sensitivities
};

/// Simulates `avatar` with its materials replaced by params.materials(avatar
/// .materials, p) and damping params.damping(p, damping) (s), along `bones`,
/// and returns the surface vertices `vertices` (indices into the avatar's
/// surface; empty = all) at steps `steps` (increasing, in [0, N]); with
/// `jacobian`, also their derivatives with respect to p.
SurfaceRun simulate_surface(const Avatar& avatar, const FitParameters& params, const VecX& p, double damping,
                            const BoneSequence& bones, const std::vector<int>& steps, const std::vector<int>& vertices,
                            bool jacobian);

}  // namespace sflsh
