#include "sflsh/sim/energies/elastic.hpp"

#include <cmath>
#include <limits>
#include <vector>

#include "sflsh/fem/tet_operators.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/sim/compression_guard.hpp"
#include "sflsh/sim/energies/sample_hessian.hpp"
#include "sflsh/sim/linearized_stiffness.hpp"

namespace sflsh {

Mat3 tet_frame(const Avatar& a, int t) {
  if (a.tet_frames.size() == 0) return Mat3::Identity();
  require(a.tet_frames.rows() == a.tet.num_elements() && a.tet_frames.cols() == 9, "tet_frames is ",
          a.tet_frames.rows(), " by ", a.tet_frames.cols(), ", expected #T = ", a.tet.num_elements(), " by 9");
  Mat3 R;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) R(r, c) = a.tet_frames(t, 3 * r + c);
  return R;
}

const RegionMaterial& tet_material(const Avatar& a, int t) {
  require(!a.materials.empty(), "avatar has no materials (need at least one RegionMaterial)");
  if (a.tet_region.size() == 0) return a.materials[0];
  require(a.tet_region.size() == a.tet.num_elements(), "tet_region has ", a.tet_region.size(),
          " entries, expected #T = ", a.tet.num_elements());
  const int r = a.tet_region[t];
  require(r >= 0 && r < int(a.materials.size()), "tet_region[", t, "] = ", r, ", expected in [0, ",
          a.materials.size(), ")");
  return a.materials[r];
}

ElasticTerm::ElasticTerm(const Avatar& a, bool project_psd, bool exact_quadratic, bool mean_dilatation)
    : num_reduced_(a.num_reduced()),
      project_psd_(project_psd),
      exact_quadratic_(exact_quadratic),
      mean_dilatation_(exact_quadratic && mean_dilatation) {
  const Cubature& cub = a.elastic;
  require(cub.weights.size() == cub.size(), "ElasticTerm: elastic cubature has ", cub.size(), " elements but ",
          cub.weights.size(), " weights");
  require(a.W.rows() == a.tet.num_nodes() && a.W.cols() == a.num_handles(), "ElasticTerm: W is ", a.W.rows(),
          " by ", a.W.cols(), ", expected #N = ", a.tet.num_nodes(), " by #K = ", a.num_handles());
  weight_ = cub.weights;
  const std::vector<fem::TetGradient> grads = fem::tet_gradients(a.tet);
  for (int k = 0; k < cub.size(); ++k) {
    const int t = cub.elements[k];
    require(t >= 0 && t < a.tet.num_elements(), "ElasticTerm: sample ", k, " has tet ", t, ", expected in [0, ",
            a.tet.num_elements(), ")");
    for (const auto& [h, v] : fem::handle_gradients(a.tet, grads[t], a.W, a.node_role, t)) {
      handle_.push_back(h);
      d_.push_back(v);
    }
    start_.push_back(int(handle_.size()));
    material_.emplace_back(tet_material(a, t), tet_frame(a, t));
    linear_hessian_.push_back(linearized_hessian(material_.back()));
  }
  const int nh = num_reduced_ / 3;
  std::vector<char> used(size_t(nh) * nh, 0);  // upper block (i, j) at nh * j + i
  for (int k = 0; k < cub.size(); ++k)
    for (int e = start_[k]; e < start_[k + 1]; ++e)
      for (int f = start_[k]; f < start_[k + 1]; ++f)
        if (handle_[e] <= handle_[f]) used[size_t(nh) * handle_[f] + handle_[e]] = 1;
  if (exact_quadratic_) {
    // ½ zᵀ K z: the linearized energy integrated over every tet that moves.
    K_ = linearized_stiffness(a, material_tet_stiffness(a), mean_dilatation_);
    K_blocks_.assign(size_t(9) * nh * nh, 0.0);
    for (int j = 0; j < nh; ++j)
      for (int i = 0; i <= j; ++i) {
        Eigen::Map<Mat3>(K_blocks_.data() + 9 * (size_t(nh) * j + i)) = K_.block<3, 3>(3 * i, 3 * j);
        if (!K_.block<3, 3>(3 * i, 3 * j).isZero(0.0)) used[size_t(nh) * j + i] = 1;
      }
  }
  for (int j = 0; j < nh; ++j)
    for (int i = 0; i <= j; ++i)
      if (used[size_t(nh) * j + i]) blocks_used_.emplace_back(i, j);
}

Mat3 ElasticTerm::deformation_gradient(int k, const VecX& z) const {
  Mat3 F = Mat3::Identity();
  for (int e = start_[k]; e < start_[k + 1]; ++e) F += z.segment<3>(3 * handle_[e]) * d_[e].transpose();
  return F;
}

double ElasticTerm::min_det(const VecX& z) const {
  double m = std::numeric_limits<double>::infinity();
  for (int k = 0; k < num_samples(); ++k) m = std::min(m, deformation_gradient(k, z).determinant());
  return m;
}

namespace {

/// Hessian scratch: the z block's upper 3x3 blocks (sample_hessian.hpp), and T.
struct ElasticCache : TermCache {
  std::vector<double> blocks;
  std::vector<Eigen::Matrix<double, 3, 9>> T;
};

}  // namespace

std::unique_ptr<TermCache> ElasticTerm::make_cache() const { return std::make_unique<ElasticCache>(); }

double ElasticTerm::compute(const StepContext& ctx, const Configuration& q, VecRef* grad, MatRef* hess) const {
  require(q.z.size() == num_reduced_, "ElasticTerm: z has ", q.z.size(), " entries, expected ", num_reduced_);
  const int z0 = ctx.layout.z_offset(), S = num_samples();
  // Without a cache (a term evaluated on its own, EnergyTerm::evaluate) a local one.
  ElasticCache local;
  auto* cache = dynamic_cast<ElasticCache*>(ctx.cache);
  ElasticCache& c = cache ? *cache : local;
  const int K = num_reduced_ / 3;
  if (hess) {
    // Only the upper blocks are accumulated; ½ zᵀ K z's Hessian K starts them.
    // Blocks outside blocks_used_ are 0 in K and never written by a sample:
    // they are zeroed once, and only the used ones are reset afterwards.
    if (c.blocks.size() != size_t(9) * K * K) c.blocks.assign(size_t(9) * K * K, 0.0);
    for (const auto& [i, j] : blocks_used_) {
      const size_t b = 9 * (size_t(K) * j + i);
      for (int v = 0; v < 9; ++v) c.blocks[b + v] = exact_quadratic_ ? K_blocks_[b + v] : 0.0;
    }
  }
  double E = 0;
  for (int k = 0; k < S; ++k) {
    const Mat3 F = deformation_gradient(k, q.z);
    Mat3 P;
    Mat9 H;
    double psi = strain_energy_density(F, material_[k], grad ? &P : nullptr, hess ? &H : nullptr, project_psd_);
    if (!std::isfinite(psi)) return std::numeric_limits<double>::infinity();
    if (exact_quadratic_) {
      // The samples carry only Ψ − Ψ₂ (Ψ₂ = ½ hᵀ H₂ h, h = vec(F − I)); ½ zᵀ K z adds Ψ₂ exactly.
      const Mat9& H2 = linear_hessian_[k];
      const Mat3 Hd = F - Mat3::Identity();
      const Vec9 h = Eigen::Map<const Vec9>(Hd.data());
      const Vec9 H2h = H2 * h;
      psi -= 0.5 * h.dot(H2h);
      if (grad) P -= Eigen::Map<const Mat3>(H2h.data());
      if (hess) H -= H2;
      if (mean_dilatation_)  // the averaged bulk share, given back beyond the onset (compression_guard.hpp)
        psi += compression_guard(F, (1.0 - kPerTetVolumeShare) * material_[k].kappa, kCompressionGuardOnset,
                                 grad ? &P : nullptr, hess ? &H : nullptr, project_psd_);
    }
    const double w = weight_[k];
    E += w * psi;
    if (grad)
      for (int e = start_[k]; e < start_[k + 1]; ++e) grad->segment<3>(z0 + 3 * handle_[e]) += w * (P * d_[e]);
    if (hess)
      add_sample_hessian_blocks(w * H, &handle_[start_[k]], &d_[start_[k]], start_[k + 1] - start_[k], K,
                                c.blocks.data(), c.T);
  }
  if (exact_quadratic_) {
    const VecX Kz = K_ * q.z;
    E += 0.5 * q.z.dot(Kz);
    if (grad) grad->segment(z0, num_reduced_) += Kz;
  }
  if (hess) add_hessian_blocks(c.blocks.data(), K, blocks_used_, z0, *hess);
  return E;
}

}  // namespace sflsh
