#pragma once
// Derivatives of the elastic term (energies/elastic.hpp, projected Hessian,
// exact quadratic split) that forward sensitivities of a one-Newton-step
// trajectory need (fit/trajectory_sensitivity.hpp; seed §1):
//
//   g(z; p) = K(p) z + Σ_k w_k G_kᵀ vec(P_k − H2_k h_k),
//   H(z; p) = K(p)   + Σ_k w_k G_kᵀ (H⁺_k − H2_k) G_k,
//
// (h_k = vec(F_k − I), G_k = ∂vec(F_k)/∂z, H⁺ the projected ∂²Ψ/∂F², H2 the
// one at F = I). A Newton step z' = z + δ, H δ = −g, has
//   dδ = −H⁻¹ (∂g/∂z dz + (∂H/∂z dz) δ + ∂g/∂p dp + (∂H/∂p dp) δ),
// and this class gives, per step, the elastic pieces of that bracket:
//   - the stiffness derivative ∂K/∂p of one region's parameter (exact: K is
//     linear in the stiffness; Poisson's ratio by a central difference of the
//     tet's 9x9 at ν ± 1e-6);
//   - the per-sample correction matrix A = Σ_k w_k G_kᵀ (H⁺_k − H_k − D_k) G_k
//     with H_k the exact (unprojected) ∂²Ψ/∂F² and D_k = ∂H⁺_k/∂F[dF_k] the
//     derivative of the projected Hessian along the step's dF_k = G_k δ, so
//     that ∂g/∂z dz + (∂H/∂z dz) δ = (H − A) dz (the symmetry of third
//     derivatives turns (∂H/∂z dz) δ into D dz; it holds where H⁺ = H; at
//     samples where the projection acts, (∂H⁺/∂z dz) δ is computed per column
//     of dz instead: on a bending box the symmetric shortcut there left errors
//     of up to 2% in the trajectory's sensitivities, the per-column one 4e-6);
//   - per parameter the vector b = Σ_{k ∈ region} w_k G_kᵀ ∂/∂p (vec(P_k − H2_k h_k)
//     + (H⁺_k − H2_k) vec(dF_k)), so that ∂g/∂p + (∂H/∂p) δ = ∂K/∂p (z + δ) + b.
// The 9x9 directional derivatives of the constitutive law (D_k, ∂/∂p of a
// sample's stress) are central differences of strain_energy_density at one
// sample (relative step 1e-5 in F, 1e-6 in the log-parameter): the law is
// smooth there, so they agree with the analytic values to ~1e-9 relative.
#include <vector>

#include "sflsh/asset/avatar.hpp"
#include "sflsh/sim/material.hpp"

namespace sflsh {

/// A material parameter of one region.
enum class MaterialParameter {
  LogYoung,  ///< log of a factor scaling young_along, young_through and young_around together
  LogFungC,  ///< log of fung_c
  Poisson    ///< poisson (dimensionless)
};

/// One region's parameter (region = index into avatar.materials).
struct RegionParameter {
  int region = 0;
  MaterialParameter kind = MaterialParameter::LogYoung;
};

class ElasticSensitivity {
 public:
  /// The elastic term's samples and materials for `avatar` (as ElasticTerm(avatar)
  /// builds them) and ∂K/∂p for each of `params`; `mean_dilatation` as the
  /// ElasticTerm's (ElasticTerm::mean_dilatation()).
  ElasticSensitivity(const Avatar& avatar, std::vector<RegionParameter> params, bool mean_dilatation = true);

  const std::vector<RegionParameter>& params() const { return params_; }
  /// ∂K/∂p_i (3K by 3K, N/m per unit of the parameter) of params()[i].
  const MatX& stiffness_derivative(int i) const { return dK_[i]; }

  /// At iterate z (3K), Newton step delta (3K) and the sensitivities S = dz/dp
  /// at the iterate (3K by m): A (3K by 3K), B (3K by #params) and C (3K by m)
  /// such that the elastic part of ∂g/∂z S + (∂H/∂z S) δ is (H − A) S + C
  /// (H the step's elastic Hessian). Samples where the projection is inactive
  /// (H⁺ = H) put their third-order term into A through D_k (header comment);
  /// the others, where symmetry does not hold, into C column by column (2m
  /// Hessian evaluations each). Throws if an element is inverted at z.
  void step_derivatives(const VecX& z, const VecX& delta, const MatX& S, MatX& A, MatX& B, MatX& C) const;

 private:
  struct Sample {
    explicit Sample(const MaterialPoint& m) : material(m) {}
    double weight = 0;     // m³
    int region = 0;
    int begin = 0, end = 0;  // range in handle_/d_
    MaterialPoint material;
    Mat9 H2;
    // per parameter acting on this sample's region: index into params_ and the material at p ± step
    std::vector<int> param;
    std::vector<MaterialPoint> plus, minus;
    std::vector<Mat9> H2_plus, H2_minus;
  };
  std::vector<RegionParameter> params_;
  std::vector<Sample> samples_;
  std::vector<int> handle_;
  std::vector<Vec3> d_;
  std::vector<MatX> dK_;
  int num_reduced_ = 0;
};

/// `material` with parameter `kind` moved by `step` (log-parameters multiply
/// by exp(step), Poisson's ratio adds it).
RegionMaterial perturbed_material(const RegionMaterial& material, MaterialParameter kind, double step);

}  // namespace sflsh
