// The fast bounded-biharmonic solver (local start, bordered solves against old
// factorizations) against a straightforward reference: dense Q, plain
// primal–dual active set started from "everything free", a fresh dense
// Cholesky every iteration.
#include <gtest/gtest.h>

#include <Eigen/Dense>

#include "box_mesh.hpp"
#include "sflsh/asset/avatar.hpp"
#include "sflsh/basis/bounded_biharmonic.hpp"
#include "sflsh/basis/handle_placement.hpp"
#include "sflsh/fem/tet_operators.hpp"

namespace sflsh::basis {
namespace {

/// min ½xᵀQx + qᵀx, 0 ≤ x ≤ 1 by textbook PDAS (Hintermüller et al. 2002)
/// with dense linear algebra; stops when the active set repeats.
VecX reference_qp(const MatX& Q, const VecX& q) {
  const Eigen::Index n = q.size();
  std::vector<char> state(size_t(n), 0);  // 0 free, 1 lower, 2 upper
  VecX x = VecX::Zero(n);
  for (int it = 0; it < 200; ++it) {
    std::vector<Eigen::Index> I;
    for (Eigen::Index i = 0; i < n; ++i) {
      if (state[size_t(i)] == 0) I.push_back(i);
      else x(i) = state[size_t(i)] == 2 ? 1.0 : 0.0;
    }
    VecX xa = x;
    for (Eigen::Index i : I) xa(i) = 0.0;
    const VecX r = -(q + Q * xa);
    MatX QII(I.size(), I.size());
    VecX rI(I.size());
    for (size_t a = 0; a < I.size(); ++a) {
      rI(Eigen::Index(a)) = r(I[a]);
      for (size_t b = 0; b < I.size(); ++b) QII(Eigen::Index(a), Eigen::Index(b)) = Q(I[a], I[b]);
    }
    const VecX xI = QII.llt().solve(rI);
    for (size_t a = 0; a < I.size(); ++a) x(I[a]) = xI(Eigen::Index(a));
    const VecX g = Q * x + q;
    bool changed = false;
    for (Eigen::Index i = 0; i < n; ++i) {
      char& s = state[size_t(i)];
      const char old = s;
      if (s == 0) s = x(i) < 0.0 ? 1 : x(i) > 1.0 ? 2 : 0;
      else if ((s == 1 && g(i) < -1e-9 * q.lpNorm<Eigen::Infinity>()) ||
               (s == 2 && g(i) > 1e-9 * q.lpNorm<Eigen::Infinity>()))
        s = 0;
      changed |= s != old;
    }
    if (!changed) return x.cwiseMax(0.0).cwiseMin(1.0);
  }
  ADD_FAILURE() << "reference PDAS did not settle";
  return x;
}

TEST(BoundedBiharmonicReference, FastPathMatchesDenseReference) {
  // A 0.3×0.1×0.2 m slab on a bone face y = 0, 8 handles.
  const TetMesh mesh = test::box_tet_mesh(12, 4, 8, 0.3, 0.1, 0.2);
  const int n = mesh.num_nodes();
  std::vector<char> is_fixed(size_t(n), 0);
  VecXi role = VecXi::Zero(n);
  for (int i = 0; i < n; ++i)
    if (mesh.nodes(i, 1) < 1e-12) role(i) = int(NodeRole::Bone);
  const int K = 8;
  const HandleSet hs = select_handles(mesh, role, K);
  std::vector<int> fixed;
  for (int k = 0; k < K; ++k) fixed.push_back(hs.nodes(k));
  for (int i = 0; i < n; ++i)
    if (role(i) != 0) fixed.push_back(i);
  for (int i : fixed) is_fixed[size_t(i)] = 1;
  const VecXi b = Eigen::Map<VecXi>(fixed.data(), Eigen::Index(fixed.size()));
  MatX bc = MatX::Zero(b.size(), K);
  for (int k = 0; k < K; ++k) bc(k, k) = 1.0;

  BbwOptions fast;
  fast.show_progress = false;
  fast.kkt_tolerance = 0.0;  // to round-off
  fast.max_border_columns = 40;  // small, so that both bordered solves and refactorizations occur
  BbwReport rep;
  const MatX W = bounded_biharmonic_qp(mesh, b, bc, fast, &rep);
  std::printf("%s\n", rep.summary().c_str());
  EXPECT_LT(rep.kkt_residual, 1e-9);
  EXPECT_LT(rep.mean_factorizations, rep.mean_iterations) << "the bordered solves were never used";

  // Reference: dense Q_ff = (L M⁻¹ L)_ff, q = Q_fb x_b.
  const MatX L = MatX(fem::stiffness_laplacian(mesh));
  const MatX Q = L * fem::lumped_mass(mesh).cwiseInverse().asDiagonal() * L;
  std::vector<int> free_nodes;
  for (int i = 0; i < n; ++i)
    if (!is_fixed[size_t(i)]) free_nodes.push_back(i);
  const int nf = int(free_nodes.size());
  MatX Qff(nf, nf);
  for (int a = 0; a < nf; ++a)
    for (int c = 0; c < nf; ++c) Qff(a, c) = Q(free_nodes[a], free_nodes[c]);
  double max_diff = 0.0;
  for (int k = 0; k < K; ++k) {
    VecX q = VecX::Zero(nf);
    for (int a = 0; a < nf; ++a) q(a) = Q(free_nodes[a], hs.nodes(k));
    const VecX x = reference_qp(Qff, q);
    for (int a = 0; a < nf; ++a) max_diff = std::max(max_diff, std::abs(x(a) - W(free_nodes[a], k)));
    for (int i : fixed) EXPECT_EQ(W(i, k), i == hs.nodes(k) ? 1.0 : 0.0);
  }
  std::printf("max |fast - reference| = %.3e\n", max_diff);
  EXPECT_LT(max_diff, 1e-8);
  EXPECT_GT(W.maxCoeff(), 0.99);  // not trivially zero
}

}  // namespace
}  // namespace sflsh::basis
