// The bench's subspace error floor (mass-weighted projection onto span(W ⊗ I₃))
// and its per-region relative errors, against closed forms and a dense
// least-squares solve.
#include "sflsh/bench/subspace_floor.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "sflsh/core/error.hpp"

namespace sflsh {
namespace {

using SpW = Eigen::SparseMatrix<double, Eigen::RowMajor>;

/// N by K random sparse non-negative weights, every column non-empty.
SpW random_basis(int N, int K, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  MatX W = MatX::Zero(N, K);
  for (int i = 0; i < N; ++i)
    for (int k = 0; k < K; ++k)
      if (U(rng) < 0.4 || i % K == k) W(i, k) = U(rng);
  return W.sparseView();
}

double rel_err(const Points& u, const Points& ref) { return (u - ref).norm() / ref.norm(); }

TEST(SubspaceFloor, DisplacementInTheSpanIsReproducedExactly) {
  const int N = 40, K = 5;
  const SpW W = random_basis(N, K, 1);
  const VecX mass = VecX::LinSpaced(N, 0.5, 2.0);
  const MatX Z = MatX::Random(K, 3);
  const Points u = W * Z;
  const SubspaceProjector P(W, mass);
  EXPECT_LT((P.coordinates(u) - Z).lpNorm<Eigen::Infinity>(), 1e-12);
  EXPECT_LT(rel_err(P.project(u), u), 1e-12);  // floor 0
}

TEST(SubspaceFloor, MassOrthogonalDisplacementGivesRelErrOne) {
  // One constant column on 6 nodes of equal mass; an alternating displacement
  // has zero mass-weighted mean, so its best approximation is 0: rel_err 1.
  const SpW W = MatX::Ones(6, 1).sparseView();
  Points u(6, 3);
  for (int i = 0; i < 6; ++i) u.row(i) = (i % 2 ? -1.0 : 1.0) * Eigen::RowVector3d(0.01, -0.02, 0.03);
  const SubspaceProjector P(W, VecX::Constant(6, 2.0));
  EXPECT_LT(P.project(u).norm(), 1e-15);
  EXPECT_DOUBLE_EQ(rel_err(P.project(u), u), 1.0);
}

TEST(SubspaceFloor, ProjectionIsTheMassWeightedMean) {
  // W = 1 on two nodes of masses 1 and 3: z = (1·a + 3·b) / 4 per coordinate.
  const SpW W = MatX::Ones(2, 1).sparseView();
  Points u(2, 3);
  u << 1, 2, 3, 5, 6, 7;
  const MatX z = SubspaceProjector(W, (VecX(2) << 1.0, 3.0).finished()).coordinates(u);
  EXPECT_NEAR(z(0, 0), (1 + 15) / 4.0, 1e-15);
  EXPECT_NEAR(z(0, 1), (2 + 18) / 4.0, 1e-15);
  EXPECT_NEAR(z(0, 2), (3 + 21) / 4.0, 1e-15);
  // A massless node does not count.
  EXPECT_NEAR(SubspaceProjector(W, (VecX(2) << 0.0, 3.0).finished()).coordinates(u)(0, 0), 5.0, 1e-15);
}

TEST(SubspaceFloor, MatchesADenseLeastSquaresSolveOfTheStackedSystem) {
  const int N = 30, K = 4;
  const SpW W = random_basis(N, K, 2);
  VecX mass = VecX::Random(N).cwiseAbs() + VecX::Constant(N, 0.1);
  const Points u = Points::Random(N, 3);
  // Independent: min ‖√M (W ⊗ I₃) z − √M vec(u)‖ over the 3K unknowns by SVD.
  MatX A = MatX::Zero(3 * N, 3 * K);
  VecX rhs(3 * N);
  const MatX Wd = MatX(W);
  for (int i = 0; i < N; ++i)
    for (int c = 0; c < 3; ++c) {
      rhs(3 * i + c) = std::sqrt(mass(i)) * u(i, c);
      for (int k = 0; k < K; ++k) A(3 * i + c, 3 * k + c) = std::sqrt(mass(i)) * Wd(i, k);
    }
  const VecX z = A.jacobiSvd(Eigen::ComputeThinU | Eigen::ComputeThinV).solve(rhs);
  const MatX Z = SubspaceProjector(W, mass).coordinates(u);
  for (int k = 0; k < K; ++k)
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(Z(k, c), z(3 * k + c), 1e-10) << "handle " << k << " coordinate " << c;
}

TEST(SubspaceFloor, RejectsBadInput) {
  const SpW W = MatX::Ones(3, 2).sparseView();  // two equal columns: singular
  EXPECT_THROW(SubspaceProjector(W, VecX::Ones(3)), Error);
  EXPECT_THROW(SubspaceProjector(MatX::Identity(3, 2).sparseView(), VecX::Ones(2)), Error);  // size
  EXPECT_THROW(SubspaceProjector(MatX::Identity(3, 2).sparseView(), (VecX(3) << 0, 1, 1).finished()), Error);  // column 0 massless
  EXPECT_THROW(SubspaceProjector(MatX::Identity(3, 2).sparseView(), (VecX(3) << 1, -1, 1).finished()), Error);
  const SubspaceProjector P(MatX::Identity(3, 2).sparseView(), VecX::Ones(3));
  EXPECT_THROW(P.project(Points::Zero(4, 3)), Error);
}

TEST(RegionRelErrors, HandMadeTwoFrames) {
  // 4 points: regions 0, 0, 1, none; 2 frames.
  VecXi region(4);
  region << 0, 0, 1, -1;
  std::vector<Points> ref(2, Points::Zero(4, 3)), u(2, Points::Zero(4, 3));
  ref[0].row(0) << 3, 0, 0;  // region 0: ref² = 9 + 16 = 25
  ref[1].row(1) << 0, 4, 0;
  u[0].row(0) << 3, 0, 0;    // error 0
  u[1].row(1) << 0, 1, 0;    // error² 9 → sqrt(9/25) = 0.6
  ref[0].row(2) << 0, 0, 2;  // region 1: ref² 4, u = 0: rel 1
  ref[1].row(3) << 9, 9, 9;  // in no region: ignored
  u[1].row(3) << -9, 0, 0;
  const std::vector<double> e = region_rel_errors(u, ref, region, 3);
  ASSERT_EQ(e.size(), 3u);
  EXPECT_DOUBLE_EQ(e[0], 0.6);
  EXPECT_DOUBLE_EQ(e[1], 1.0);
  EXPECT_TRUE(std::isnan(e[2]));  // no points
  // Only the common frames count: a third frame of u alone changes nothing.
  u.push_back(Points::Ones(4, 3));
  EXPECT_DOUBLE_EQ(region_rel_errors(u, ref, region, 3)[0], 0.6);
  EXPECT_THROW(region_rel_errors(u, ref, region, 1), Error);  // label 1 out of range
  EXPECT_THROW(region_rel_errors(u, ref, VecXi::Zero(3), 1), Error);  // label count
}

/// Affine handles: with rows of W normalized to a partition of unity, any affine field
/// x ↦ A x + b is reproduced exactly (floor 0), which the translational basis cannot do; the
/// columns are laid out as documented (k: W_·k; K + 3k + c: W_·k (x_c − c_{k,c})), checked
/// entry by entry against a hand computation.
TEST(SubspaceFloor, AffineHandlesReproduceAffineFieldsWhereWeightsSumToOne) {
  const int N = 50, K = 4;
  MatX Wd = MatX(random_basis(N, K, 3));
  for (int i = 0; i < N; ++i) Wd.row(i) /= Wd.row(i).sum();
  const SpW W = Wd.sparseView();
  const Points x = Points::Random(N, 3);
  const Points c = Points::Random(K, 3);
  const SpW Wa = affine_handle_weights(W, x, c);
  ASSERT_EQ(Wa.rows(), N);
  ASSERT_EQ(Wa.cols(), 4 * K);
  const MatX Wad = MatX(Wa);
  for (int i = 0; i < N; i += 7)
    for (int k = 0; k < K; ++k) {
      EXPECT_EQ(Wad(i, k), Wd(i, k));
      for (int a = 0; a < 3; ++a) EXPECT_NEAR(Wad(i, K + 3 * k + a), Wd(i, k) * (x(i, a) - c(k, a)), 1e-15);
    }
  Mat3 A;
  A << 0.01, -0.02, 0.005, 0.03, 0.002, -0.01, -0.004, 0.02, 0.015;
  const Vec3 b(0.003, -0.001, 0.002);
  const Points u = (x * A.transpose()).rowwise() + b.transpose();
  const VecX mass = VecX::LinSpaced(N, 0.5, 2.0);
  EXPECT_LT(rel_err(SubspaceProjector(Wa, mass).project(u), u), 1e-10);
  EXPECT_GT(rel_err(SubspaceProjector(W, mass).project(u), u), 0.05) << "translations alone miss a rotation field";
  EXPECT_THROW(affine_handle_weights(W, Points::Zero(N - 1, 3), c), Error);
  EXPECT_THROW(affine_handle_weights(W, x, Points::Zero(K + 1, 3)), Error);
}

}  // namespace
}  // namespace sflsh
