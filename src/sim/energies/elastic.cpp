#include "sflsh/sim/energies/elastic.hpp"

#include <cmath>
#include <limits>
#include <map>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

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
    frame_.push_back(tet_frame(a, t));
    material_.push_back(&tet_material(a, t));
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
  const int z0 = ctx.layout.z_offset(), r = num_reduced_, S = num_samples();
  // Projected Hessian as Σ_k Y_kᵀ Y_k, Y_k = Lᵀ G_k (9 by 3m_k) with
  // c_k ΠPSD(∂²Ψ/∂F²) = L Lᵀ. Dense basis: stack the Y_k and do one symmetric
  // rank-9S update over all of z; sparse basis: form each Y_kᵀ Y_k and scatter.
  double local_cost = 0;
  for (int k = 0; k < S; ++k) local_cost += std::pow(3.0 * (start_[k + 1] - start_[k]), 2);
  const bool dense = local_cost >= 0.3 * double(S) * r * r;
  MatX Y;
  if (hess && project_psd_ && dense) Y.setZero(9 * S, r);
  MatX Yk, YtY;  // per-sample buffers, reused
  double E = 0;
  for (int k = 0; k < S; ++k) {
    const Mat3 F = deformation_gradient(k, q.z);
    Mat3 P;
    Mat9 H;
    const double psi = strain_energy_density(F, frame_[k], *material_[k], grad ? &P : nullptr,
                                             hess ? &H : nullptr, false);
    if (!std::isfinite(psi)) return std::numeric_limits<double>::infinity();
    E += weight_[k] * psi;
    if (grad)
      for (int e = start_[k]; e < start_[k + 1]; ++e)
        grad->segment<3>(z0 + 3 * handle_[e]) += weight_[k] * (P * d_[e]);
    if (!hess) continue;
    const int m = start_[k + 1] - start_[k];
    if (!project_psd_) {
      // Exact Hessian c_k G_kᵀ H G_k (for derivative checks).
      MatX G = MatX::Zero(9, 3 * m);
      for (int e = 0; e < m; ++e)
        for (int c = 0; c < 3; ++c)
          for (int b = 0; b < 3; ++b) G(c + 3 * b, 3 * e + c) = d_[start_[k] + e][b];
      const MatX Hk = weight_[k] * G.transpose() * H * G;
      for (int i = 0; i < m; ++i)
        for (int j = 0; j < m; ++j)
          hess->block<3, 3>(z0 + 3 * handle_[start_[k] + i], z0 + 3 * handle_[start_[k] + j]) += Hk.block<3, 3>(3 * i, 3 * j);
      continue;
    }
    // Lᵀ: Cholesky when already positive definite (cheap), else eigenvalue clamping.
    Mat9 Lt;
    Eigen::LLT<Mat9> llt(H);
    if (llt.info() == Eigen::Success) {
      Lt = std::sqrt(weight_[k]) * llt.matrixU().toDenseMatrix();
    } else {
      Eigen::SelfAdjointEigenSolver<Mat9> eig(H);
      const Vec9 root = (weight_[k] * eig.eigenvalues().cwiseMax(0.0)).cwiseSqrt();
      Lt = root.asDiagonal() * eig.eigenvectors().transpose();
    }
    // G_k(a + 3b, 3h + c) = δ_ac d_h[b]  ⇒  (Lᵀ G_k)(i, 3e + c) = Σ_b Lᵀ(i, c + 3b) d_e[b].
    Yk.resize(9, 3 * m);
    for (int e = 0; e < m; ++e) {
      const Vec3& d = d_[start_[k] + e];
      for (int c = 0; c < 3; ++c) Yk.col(3 * e + c) = Lt.col(c) * d[0] + Lt.col(c + 3) * d[1] + Lt.col(c + 6) * d[2];
    }
    if (dense) {
      for (int e = 0; e < m; ++e) Y.block(9 * k, 3 * handle_[start_[k] + e], 9, 3) = Yk.middleCols(3 * e, 3);
    } else {
      YtY.resize(Yk.cols(), Yk.cols());
      YtY.noalias() = Yk.transpose() * Yk;
      for (int i = 0; i < m; ++i)
        for (int j = 0; j < m; ++j)
          hess->block<3, 3>(z0 + 3 * handle_[start_[k] + i], z0 + 3 * handle_[start_[k] + j]) += YtY.block<3, 3>(3 * i, 3 * j);
    }
  }
  if (hess && project_psd_ && dense) {
    auto block = hess->block(z0, z0, r, r);
    block.selfadjointView<Eigen::Lower>().rankUpdate(Y.transpose());
    block.triangularView<Eigen::StrictlyUpper>() = block.transpose();
  }
  return E;
}

}  // namespace sflsh
