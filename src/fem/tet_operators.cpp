#include "sflsh/fem/tet_operators.hpp"

#include <algorithm>
#include <vector>

#include "sflsh/core/error.hpp"

namespace sflsh::fem {
namespace {

Mat3 edge_matrix(const TetMesh& mesh, int e) {
  const auto t = mesh.elements.row(e);
  Mat3 D;
  for (int c = 0; c < 3; ++c) D.col(c) = (mesh.nodes.row(t(c + 1)) - mesh.nodes.row(t(0))).transpose();
  return D;
}

void check_indices(const TetMesh& mesh) {
  const int n = mesh.num_nodes();
  for (int e = 0; e < mesh.num_elements(); ++e)
    for (int a = 0; a < 4; ++a) {
      const int i = mesh.elements(e, a);
      require(i >= 0 && i < n, "tet mesh: element ", e, " refers to node ", i, ", expected 0..", n - 1);
    }
}

}  // namespace

VecX tet_volumes(const TetMesh& mesh) {
  check_indices(mesh);
  VecX vol(mesh.num_elements());
  for (int e = 0; e < mesh.num_elements(); ++e) vol(e) = edge_matrix(mesh, e).determinant() / 6.0;
  return vol;
}

std::vector<TetGradient> tet_gradients(const TetMesh& mesh) {
  check_indices(mesh);
  std::vector<TetGradient> grads(mesh.num_elements());
  for (int e = 0; e < mesh.num_elements(); ++e) {
    const Mat3 D = edge_matrix(mesh, e);
    const double det = D.determinant();
    // Relative threshold: a sliver with volume ~1e-12 of its edge cube is degenerate.
    const double scale = D.colwise().norm().prod();
    require(det > 1e-12 * scale, "tet mesh: element ", e, " is degenerate or inverted (6·volume = ", det,
            " m^3), expected positive orientation");
    // φ_{1..3} = rows of D⁻¹ applied to (x − x0); φ_0 = 1 − Σ.
    const Mat3 Dinv = D.inverse();
    grads[e].bottomRows<3>() = Dinv;
    grads[e].row(0) = -Dinv.colwise().sum();
  }
  return grads;
}

std::vector<std::pair<int, Vec3>> handle_gradients(const TetMesh& mesh, const TetGradient& grad,
                                                   const Eigen::SparseMatrix<double, Eigen::RowMajor>& W,
                                                   const VecXi& node_role, int t) {
  std::vector<std::pair<int, Vec3>> out;
  for (int c = 0; c < 4; ++c) {
    const int n = mesh.elements(t, c);
    if (node_role.size() && node_role[n] != 0) continue;  // Dirichlet: u = 0
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(W, n); it; ++it) {
      auto pos = std::lower_bound(out.begin(), out.end(), int(it.col()),
                                  [](const auto& e, int k) { return e.first < k; });
      if (pos == out.end() || pos->first != it.col()) pos = out.insert(pos, {int(it.col()), Vec3::Zero()});
      pos->second += it.value() * grad.row(c).transpose();
    }
  }
  return out;
}

Eigen::SparseMatrix<double> stiffness_laplacian(const TetMesh& mesh, const VecX& tet_weight) {
  require(tet_weight.size() == 0 || tet_weight.size() == mesh.num_elements(), "stiffness_laplacian: ",
          tet_weight.size(), " tet weights for ", mesh.num_elements(), " tets");
  VecX vol = tet_volumes(mesh);
  if (tet_weight.size() > 0) vol = vol.cwiseProduct(tet_weight);
  const auto grads = tet_gradients(mesh);
  std::vector<Eigen::Triplet<double>> trip;
  trip.reserve(16 * size_t(mesh.num_elements()));
  for (int e = 0; e < mesh.num_elements(); ++e) {
    const Eigen::Matrix4d Ke = vol(e) * grads[e] * grads[e].transpose();
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b) trip.emplace_back(mesh.elements(e, a), mesh.elements(e, b), Ke(a, b));
  }
  Eigen::SparseMatrix<double> L(mesh.num_nodes(), mesh.num_nodes());
  L.setFromTriplets(trip.begin(), trip.end());
  return L;
}

VecX lumped_mass(const TetMesh& mesh) {
  const VecX vol = tet_volumes(mesh);
  VecX m = VecX::Zero(mesh.num_nodes());
  for (int e = 0; e < mesh.num_elements(); ++e)
    for (int a = 0; a < 4; ++a) m(mesh.elements(e, a)) += vol(e) / 4.0;
  return m;
}

Eigen::SparseMatrix<double> consistent_mass(const TetMesh& mesh) {
  const VecX vol = tet_volumes(mesh);
  std::vector<Eigen::Triplet<double>> trip;
  trip.reserve(16 * size_t(mesh.num_elements()));
  for (int e = 0; e < mesh.num_elements(); ++e)
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b)
        trip.emplace_back(mesh.elements(e, a), mesh.elements(e, b), vol(e) * (a == b ? 2.0 : 1.0) / 20.0);
  Eigen::SparseMatrix<double> M(mesh.num_nodes(), mesh.num_nodes());
  M.setFromTriplets(trip.begin(), trip.end());
  return M;
}

Eigen::RowVectorXd integrate_linear(const TetMesh& mesh, const MatX& f) {
  require(f.rows() == mesh.num_nodes(), "integrate_linear: field has ", f.rows(), " rows, expected #N = ",
          mesh.num_nodes());
  const VecX vol = tet_volumes(mesh);
  Eigen::RowVectorXd sum = Eigen::RowVectorXd::Zero(f.cols());
  for (int e = 0; e < mesh.num_elements(); ++e) {
    Eigen::RowVectorXd mean = Eigen::RowVectorXd::Zero(f.cols());
    for (int a = 0; a < 4; ++a) mean += f.row(mesh.elements(e, a));
    sum += vol(e) * 0.25 * mean;
  }
  return sum;
}

}  // namespace sflsh::fem
