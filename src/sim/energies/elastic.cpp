#include "sflsh/sim/energies/elastic.hpp"

#include <cmath>
#include <limits>
#include <map>

#include "sflsh/core/error.hpp"

namespace sflsh {

MatXr tet_shape_gradients(const TetMesh& mesh) {
  MatXr grads(mesh.num_elements(), 12);
  for (int t = 0; t < mesh.num_elements(); ++t) {
    const Vec3 x0 = mesh.nodes.row(mesh.elements(t, 0)).transpose();
    Mat3 Dm;
    for (int c = 1; c < 4; ++c) Dm.col(c - 1) = mesh.nodes.row(mesh.elements(t, c)).transpose() - x0;
    const double det = Dm.determinant();
    require(det > 0 && std::isfinite(det), "tet_shape_gradients: tet ", t, " has 6·volume ", det,
            ", expected > 0 (positively oriented, non-degenerate)");
    // N_c(x) = (Dm⁻¹ (x − x0))_c for c = 1..3, N_0 = 1 − Σ: ∇N_c = row c−1 of Dm⁻¹.
    const Mat3 Dinv = Dm.inverse();
    Vec3 g0 = Vec3::Zero();
    for (int c = 1; c < 4; ++c) {
      grads.block<1, 3>(t, 3 * c) = Dinv.row(c - 1);
      g0 -= Dinv.row(c - 1).transpose();
    }
    grads.block<1, 3>(t, 0) = g0.transpose();
  }
  return grads;
}

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

ElasticTerm::ElasticTerm(const Avatar& a, bool project_psd) : num_reduced_(a.num_reduced()), project_psd_(project_psd) {
  const Cubature& cub = a.elastic;
  require(cub.weights.size() == cub.size(), "ElasticTerm: elastic cubature has ", cub.size(), " elements but ",
          cub.weights.size(), " weights");
  require(a.W.rows() == a.tet.num_nodes() && a.W.cols() == a.num_handles(), "ElasticTerm: W is ", a.W.rows(),
          " by ", a.W.cols(), ", expected #N = ", a.tet.num_nodes(), " by #K = ", a.num_handles());
  // Only the tets used by the cubature need shape gradients.
  weight_ = cub.weights;
  for (int k = 0; k < cub.size(); ++k) {
    const int t = cub.elements[k];
    require(t >= 0 && t < a.tet.num_elements(), "ElasticTerm: sample ", k, " has tet ", t, ", expected in [0, ",
            a.tet.num_elements(), ")");
    TetMesh one;
    one.nodes.resize(4, 3);
    one.elements.resize(1, 4);
    for (int c = 0; c < 4; ++c) {
      one.nodes.row(c) = a.tet.nodes.row(a.tet.elements(t, c));
      one.elements(0, c) = c;
    }
    const MatXr grad = tet_shape_gradients(one);
    std::map<int, Vec3> d;
    for (int c = 0; c < 4; ++c) {
      const int n = a.tet.elements(t, c);
      if (a.node_role.size() && a.node_role[n] != int(NodeRole::Simulated)) continue;  // Dirichlet u = 0
      for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(a.W, n); it; ++it) {
        auto [pos, inserted] = d.try_emplace(int(it.col()), Vec3::Zero());
        pos->second += it.value() * grad.block<1, 3>(0, 3 * c).transpose();
      }
    }
    for (const auto& [h, v] : d) {
      handle_.push_back(h);
      d_.push_back(v);
    }
    start_.push_back(int(handle_.size()));
    material_.emplace_back(tet_material(a, t), tet_frame(a, t));
  }
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

double ElasticTerm::evaluate(const StepContext& ctx, const Configuration& q, VecX* grad, MatX* hess) const {
  require(q.z.size() == num_reduced_, "ElasticTerm: z has ", q.z.size(), " entries, expected ", num_reduced_);
  const int z0 = ctx.layout.z_offset(), S = num_samples();
  double E = 0;
  std::vector<Eigen::Matrix<double, 3, 9>> T;  // per handle of the sample, reused
  for (int k = 0; k < S; ++k) {
    const Mat3 F = deformation_gradient(k, q.z);
    Mat3 P;
    Mat9 H;
    const double psi = strain_energy_density(F, material_[k], grad ? &P : nullptr, hess ? &H : nullptr, project_psd_);
    if (!std::isfinite(psi)) return std::numeric_limits<double>::infinity();
    const double w = weight_[k];
    E += w * psi;
    if (grad)
      for (int e = start_[k]; e < start_[k + 1]; ++e) grad->segment<3>(z0 + 3 * handle_[e]) += w * (P * d_[e]);
    if (!hess) continue;
    // c_k G_kᵀ H G_k with G_k(a + 3b, 3e + c) = δ_ac d_e[b], block by block:
    //   T_e = Σ_b d_e[b] H(3b..3b+2, :)   (3x9),
    //   block(e, f) = c_k Σ_b' T_e(:, 3b'..3b'+2) d_f[b'].
    const int m = start_[k + 1] - start_[k];
    T.resize(m);
    for (int e = 0; e < m; ++e) {
      const Vec3& d = d_[start_[k] + e];
      T[e] = w * (d[0] * H.middleRows<3>(0) + d[1] * H.middleRows<3>(3) + d[2] * H.middleRows<3>(6));
    }
    for (int e = 0; e < m; ++e) {
      const int row = z0 + 3 * handle_[start_[k] + e];
      for (int f = e; f < m; ++f) {
        const Vec3& d = d_[start_[k] + f];
        const Mat3 block = d[0] * T[e].leftCols<3>() + d[1] * T[e].middleCols<3>(3) + d[2] * T[e].rightCols<3>();
        const int col = z0 + 3 * handle_[start_[k] + f];
        hess->block<3, 3>(row, col) += block;
        if (f != e) hess->block<3, 3>(col, row) += block.transpose();
      }
    }
  }
  return E;
}

}  // namespace sflsh
