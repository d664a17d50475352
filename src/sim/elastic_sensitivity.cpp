#include "sflsh/sim/elastic_sensitivity.hpp"

#include <cmath>

#include "sflsh/core/error.hpp"
#include "sflsh/fem/tet_operators.hpp"
#include "sflsh/sim/energies/elastic.hpp"
#include "sflsh/sim/energies/sample_hessian.hpp"
#include "sflsh/sim/linearized_stiffness.hpp"

namespace sflsh {
namespace {

constexpr double kParameterStep = 1e-6;  // central-difference step in the (log-)parameter
constexpr double kStrainStep = 1e-5;     // central-difference step of F along dF (relative to ‖dF‖ = 1)

Eigen::Map<const Vec9> vec(const Mat3& M) { return Eigen::Map<const Vec9>(M.data()); }

/// vec(P − H2 h) + (H⁺ − H2) dF: the sample's part of g + H δ (per unit weight, before Gᵀ).
Vec9 newton_residual(const Mat3& F, const MaterialPoint& m, const Mat9& H2, const Vec9& dF) {
  Mat3 P;
  Mat9 H;
  const double psi = strain_energy_density(F, m, &P, &H, true);
  require(std::isfinite(psi), "ElasticSensitivity: an element is inverted at the step's iterate");
  const Mat3 Hd = F - Mat3::Identity();
  return vec(P) - H2 * vec(Hd) + (H - H2) * dF;
}

/// Gᵀ v for a sample: grad(z-block of handle e) += v as 3x3 times d_e.
void add_sample_gradient(const Vec9& v, const int* handle, const Vec3* d, int m, Eigen::Ref<VecX> out) {
  const Eigen::Map<const Mat3> V(v.data());
  for (int e = 0; e < m; ++e) out.segment<3>(3 * handle[e]) += V * d[e];
}

}  // namespace

RegionMaterial perturbed_material(const RegionMaterial& m, MaterialParameter kind, double step) {
  RegionMaterial r = m;
  switch (kind) {
    case MaterialParameter::LogYoung: r.scale_young(std::exp(step)); break;
    case MaterialParameter::LogFungC: r.fung_c *= std::exp(step); break;
    case MaterialParameter::Poisson: r.poisson += step; break;
  }
  return r;
}

ElasticSensitivity::ElasticSensitivity(const Avatar& a, std::vector<RegionParameter> params, bool mean_dilatation)
    : params_(std::move(params)), num_reduced_(a.num_reduced()) {
  for (const RegionParameter& p : params_)
    require(p.region >= 0 && p.region < int(a.materials.size()), "ElasticSensitivity: region ", p.region,
            ", expected in [0, ", a.materials.size(), ")");
  const int R = int(a.materials.size());
  std::vector<std::vector<int>> region_params(R);
  for (int i = 0; i < int(params_.size()); ++i) region_params[params_[i].region].push_back(i);

  const std::vector<fem::TetGradient> grads = fem::tet_gradients(a.tet);
  const Cubature& cub = a.elastic;
  samples_.reserve(cub.size());
  for (int k = 0; k < cub.size(); ++k) {
    const int t = cub.elements[k];
    const Mat3 frame = tet_frame(a, t);
    const RegionMaterial& mat = tet_material(a, t);
    Sample s{MaterialPoint(mat, frame)};
    s.weight = cub.weights[k];
    s.region = a.tet_region.size() ? a.tet_region[t] : 0;
    s.begin = int(handle_.size());
    for (const auto& [h, v] : fem::handle_gradients(a.tet, grads[t], a.W, a.node_role, t)) {
      handle_.push_back(h);
      d_.push_back(v);
    }
    s.end = int(handle_.size());
    s.H2 = linearized_hessian(s.material);
    for (int i : region_params[s.region]) {
      s.param.push_back(i);
      s.plus.emplace_back(perturbed_material(mat, params_[i].kind, kParameterStep), frame);
      s.minus.emplace_back(perturbed_material(mat, params_[i].kind, -kParameterStep), frame);
      s.H2_plus.push_back(linearized_hessian(s.plus.back()));
      s.H2_minus.push_back(linearized_hessian(s.minus.back()));
    }
    samples_.push_back(std::move(s));
  }

  // ∂K/∂p: the exact quadratic ½ zᵀ K z sums every moving tet's volume · H2,
  // linearly in H2 also with mean dilatation (linearized_stiffness.hpp).
  dK_.assign(params_.size(), MatX());
  for (int i = 0; i < int(params_.size()); ++i) {
    const RegionParameter p = params_[i];
    if (p.kind == MaterialParameter::LogFungC) {  // H2 does not depend on c
      dK_[i] = MatX::Zero(num_reduced_, num_reduced_);
      continue;
    }
    dK_[i] = linearized_stiffness(a, [&a, p](int t, Mat9& dH2) {
      if ((a.tet_region.size() ? a.tet_region[t] : 0) != p.region) return false;
      const Mat3 frame = tet_frame(a, t);
      const RegionMaterial& mat = tet_material(a, t);
      if (p.kind == MaterialParameter::LogYoung) {
        dH2 = linearized_hessian(MaterialPoint(mat, frame));  // H2 ∝ the Young's factor
      } else {
        dH2 = (linearized_hessian(MaterialPoint(perturbed_material(mat, p.kind, kParameterStep), frame)) -
               linearized_hessian(MaterialPoint(perturbed_material(mat, p.kind, -kParameterStep), frame))) /
              (2 * kParameterStep);
        dH2 = 0.5 * (dH2 + dH2.transpose()).eval();
      }
      return true;
    }, mean_dilatation);
  }
}

void ElasticSensitivity::step_derivatives(const VecX& z, const VecX& delta, const MatX& S, MatX& A, MatX& B,
                                          MatX& C) const {
  require(z.size() == num_reduced_ && delta.size() == num_reduced_ && S.rows() == num_reduced_,
          "ElasticSensitivity: z, delta and S have ", z.size(), ", ", delta.size(), " and ", S.rows(),
          " rows, expected ", num_reduced_);
  A = MatX::Zero(num_reduced_, num_reduced_);
  B = MatX::Zero(num_reduced_, int(params_.size()));
  C = MatX::Zero(num_reduced_, S.cols());
  std::vector<Eigen::Matrix<double, 3, 9>> T;
  // The projected Hessian's derivative along direction dG (9x9), by a central difference.
  auto hessian_derivative = [](const Mat3& F, const Mat3& dG, const MaterialPoint& m) {
    const double t = kStrainStep / dG.norm();
    Mat9 Hplus, Hminus;
    const double ep = strain_energy_density(F + t * dG, m, nullptr, &Hplus, true);
    const double em = strain_energy_density(F - t * dG, m, nullptr, &Hminus, true);
    require(std::isfinite(ep) && std::isfinite(em), "ElasticSensitivity: an element inverts along the step");
    return Mat9((Hplus - Hminus) / (2 * t));
  };
  for (const Sample& s : samples_) {
    const int m = s.end - s.begin;
    if (m == 0) continue;
    const int* handle = &handle_[s.begin];
    const Vec3* d = &d_[s.begin];
    Mat3 F = Mat3::Identity(), dF = Mat3::Zero();
    for (int e = 0; e < m; ++e) {
      F += z.segment<3>(3 * handle[e]) * d[e].transpose();
      dF += delta.segment<3>(3 * handle[e]) * d[e].transpose();
    }
    Mat9 Hp, H;
    require(std::isfinite(strain_energy_density(F, s.material, nullptr, &Hp, true)),
            "ElasticSensitivity: an element is inverted at the step's iterate");
    strain_energy_density(F, s.material, nullptr, &H, false);
    Mat9 corr = Hp - H;  // H⁺ − H: the step's Hessian is not ∂g/∂z under compression
    if (dF.norm() > 0) {
      if (corr.squaredNorm() == 0) {
        // No projection here: third derivatives are symmetric, (∂H/∂z S_j) δ = (∂H/∂z δ) S_j.
        const Mat9 D = hessian_derivative(F, dF, s.material);
        corr -= 0.5 * (D + D.transpose());
      } else {
        // Projected: the derivative along each column, applied to dF.
        const Vec9 dFv = vec(dF);
        for (int j = 0; j < S.cols(); ++j) {
          Mat3 dG = Mat3::Zero();
          for (int e = 0; e < m; ++e) dG += S.col(j).segment<3>(3 * handle[e]) * d[e].transpose();
          if (dG.norm() == 0) continue;
          add_sample_gradient(s.weight * (hessian_derivative(F, dG, s.material) * dFv), handle, d, m, C.col(j));
        }
      }
    }
    if (corr.squaredNorm() > 0) add_sample_hessian(s.weight * corr, handle, d, m, 0, A, T);
    const Vec9 dFv = vec(dF);
    for (size_t j = 0; j < s.param.size(); ++j) {
      const Vec9 db = (newton_residual(F, s.plus[j], s.H2_plus[j], dFv) -
                       newton_residual(F, s.minus[j], s.H2_minus[j], dFv)) /
                      (2 * kParameterStep);
      add_sample_gradient(s.weight * db, handle, d, m, B.col(s.param[j]));
    }
  }
}

}  // namespace sflsh
