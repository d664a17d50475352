#include "sflsh/sim/linearized_stiffness.hpp"

#include <vector>

#include "sflsh/core/error.hpp"
#include "sflsh/fem/tet_operators.hpp"
#include "sflsh/sim/energies/elastic.hpp"
#include "sflsh/sim/energies/sample_hessian.hpp"

namespace sflsh {

VecXi dilatation_cells(const Avatar& a) {
  const int T = a.tet.num_elements(), K = a.num_handles();
  require(a.W.rows() == a.tet.num_nodes() && a.W.cols() == K, "dilatation_cells: W is ", a.W.rows(), " by ",
          a.W.cols(), ", expected #N = ", a.tet.num_nodes(), " by #K = ", K);
  VecXi cell = VecXi::Constant(T, -1);
  VecX sum = VecX::Zero(K);
  std::vector<int> touched;
  for (int t = 0; t < T; ++t) {
    touched.clear();
    for (int c = 0; c < 4; ++c) {
      const int n = a.tet.elements(t, c);
      if (a.node_role.size() && a.node_role[n] != int(NodeRole::Simulated)) continue;  // Dirichlet: u = 0
      for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(a.W, n); it; ++it) {
        if (sum[it.col()] == 0) touched.push_back(int(it.col()));
        sum[it.col()] += it.value();
      }
    }
    double best = 0;
    for (int k : touched) {
      // Ties go to the lower handle index, so the cells do not depend on the visiting order.
      if (sum[k] > best || (sum[k] == best && best > 0 && k < cell[t])) best = sum[k], cell[t] = k;
      sum[k] = 0;
    }
  }
  return cell;
}

TetStiffness material_tet_stiffness(const Avatar& a) {
  return [&a](int t, Mat9& H) {
    H = linearized_hessian(MaterialPoint(tet_material(a, t), tet_frame(a, t)));
    return true;
  };
}

MatX linearized_stiffness(const Avatar& a, const TetStiffness& tet_stiffness, bool mean_dilatation,
                          double per_tet_share) {
  require(per_tet_share >= 0 && per_tet_share <= 1, "linearized_stiffness: per-tet volume share ", per_tet_share,
          " is outside [0, 1]");
  const int n = a.num_reduced(), K = a.num_handles();
  MatX Kz = MatX::Zero(n, n);
  const VecX volume = fem::tet_volumes(a.tet);
  const std::vector<fem::TetGradient> grads = fem::tet_gradients(a.tet);
  const VecXi cell = mean_dilatation ? dilatation_cells(a) : VecXi();
  Vec9 v = Vec9::Zero();
  v[0] = v[4] = v[8] = 1.0;
  const Mat9 P = Mat9::Identity() - v * v.transpose() / 3.0;
  // Per cell: g_c (before division by V_c), a_c, s_c, V_c.
  std::vector<VecX> g, ac;
  VecX Vc, sc;
  if (mean_dilatation) {
    g.assign(size_t(K), VecX());
    ac.assign(size_t(K), VecX());
    Vc = VecX::Zero(K);
    sc = VecX::Zero(K);
  }
  std::vector<Eigen::Matrix<double, 3, 9>> scratch;
  std::vector<int> handle;
  std::vector<Vec3> d;
  Mat9 H;
  for (int t = 0; t < a.tet.num_elements(); ++t) {
    handle.clear();
    d.clear();
    for (const auto& [h, dv] : fem::handle_gradients(a.tet, grads[t], a.W, a.node_role, t))
      handle.push_back(h), d.push_back(dv);
    if (handle.empty()) continue;
    const int m = int(handle.size());
    const int c = mean_dilatation ? cell[t] : -1;
    if (c >= 0) {
      if (g[size_t(c)].size() == 0) g[size_t(c)] = ac[size_t(c)] = VecX::Zero(n);
      for (int e = 0; e < m; ++e) g[size_t(c)].segment<3>(3 * handle[e]) += volume[t] * d[e];  // ∂(V tr ∇u)/∂z
      Vc[c] += volume[t];
    }
    if (!tet_stiffness(t, H)) continue;
    H *= volume[t];
    if (c < 0) {
      add_sample_hessian(H, handle.data(), d.data(), m, 0, Kz, scratch);
      continue;
    }
    // (1 − α) of the averaged form and α of the plain one: the deviatoric
    // P H P is common; the cell terms below are linear in H, so they take (1 − α) H.
    add_sample_hessian(per_tet_share * H + (1 - per_tet_share) * (P * H * P), handle.data(), d.data(), m, 0, Kz,
                       scratch);
    H *= 1 - per_tet_share;
    const Vec9 y = P * H * v;
    const Eigen::Map<const Mat3> Y(y.data());
    for (int e = 0; e < m; ++e) ac[size_t(c)].segment<3>(3 * handle[e]) += Y * d[e];  // Bᵀ y
    sc[c] += v.dot(H * v);
  }
  for (int c = 0; mean_dilatation && c < K; ++c) {
    if (Vc[c] <= 0) continue;
    const VecX gc = g[size_t(c)] / Vc[c];
    Kz.noalias() += (ac[size_t(c)] * gc.transpose() + gc * ac[size_t(c)].transpose()) / 3.0;
    Kz.noalias() += (sc[c] / 9.0) * gc * gc.transpose();
  }
  return Kz;
}

}  // namespace sflsh
