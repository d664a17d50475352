// The patch block's sparse Cholesky factor against dense linear algebra.
#include <gtest/gtest.h>

#include <Eigen/Dense>

#include "sim/energies/contact_patch_cholesky.hpp"

namespace sflsh {
namespace {

using contact_patch_detail::PatchCholesky;

// A chain of `n` nodes (3 DoFs each) coupled to their neighbours: a
// block-tridiagonal SPD matrix, diagonally dominant, with distinct entries.
MatX chain(int n, double coupling) {
  MatX A = MatX::Zero(3 * n, 3 * n);
  for (int i = 0; i < n; ++i) {
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) A(3 * i + a, 3 * i + b) = a == b ? 10.0 + i + a : 0.5 / (1 + a + b);
    if (i + 1 < n)
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) A(3 * i + a, 3 * i + 3 + b) = A(3 * i + 3 + b, 3 * i + a) = coupling * (1 + a - b);
  }
  return A;
}

VecX ramp(long n) {
  VecX b(n);
  for (long i = 0; i < n; ++i) b[i] = 1.0 + 0.25 * double(i % 7) - 0.1 * double(i);
  return b;
}

TEST(PatchCholesky, SolvesTheBlockAndItsShiftedSums) {
  const MatX A = chain(5, 0.7);
  PatchCholesky f;
  ASSERT_TRUE(f.factor(A));
  EXPECT_EQ(f.rows(), 15);
  const VecX b = ramp(15);
  EXPECT_LT((A * f.solve(b) - b).norm(), 1e-12 * b.norm());
  // A − B + s I and A + B, read from the two dense matrices.
  const MatX B = chain(5, 0.2) * 0.3;
  ASSERT_TRUE(f.factor(A, &B, -1.0, 0.5));
  const MatX M = A - B + 0.5 * MatX::Identity(15, 15);
  EXPECT_LT((M * f.solve(b) - b).norm(), 1e-12 * b.norm());
  ASSERT_TRUE(f.factor(A, &B, 1.0));
  EXPECT_LT(((A + B) * f.solve(b) - b).norm(), 1e-12 * b.norm());
}

TEST(PatchCholesky, ANonzeroOutsideThePatternWidensIt) {
  // First factored on the chain's pattern; then node 0 couples to node 4,
  // which the first analysis did not hold: dropping it would solve another matrix.
  MatX A = chain(5, 0.7);
  PatchCholesky f;
  ASSERT_TRUE(f.factor(A));
  A(0, 13) = A(13, 0) = 1.5;
  A(2, 12) = A(12, 2) = -0.75;
  ASSERT_TRUE(f.factor(A));
  const VecX b = ramp(15);
  EXPECT_LT((A * f.solve(b) - b).norm(), 1e-12 * b.norm());
  // A smaller matrix after a larger one: the analysis follows the size.
  const MatX small = chain(2, 0.3);
  ASSERT_TRUE(f.factor(small));
  EXPECT_EQ(f.rows(), 6);
  EXPECT_LT((small * f.solve(ramp(6)) - ramp(6)).norm(), 1e-12 * ramp(6).norm());
}

TEST(PatchCholesky, ANonzeroMovedOrOnlyInTheSecondMatrixWidensThePattern) {
  // Column 0 first holds (13, 0); then that entry is zero and (14, 0) is not:
  // the column's nonzero count is unchanged, but one of them is new.
  MatX A = chain(5, 0.7);
  A(0, 13) = A(13, 0) = 1.5;
  PatchCholesky f;
  ASSERT_TRUE(f.factor(A));
  A(0, 13) = A(13, 0) = 0.0;
  A(0, 14) = A(14, 0) = -1.25;
  ASSERT_TRUE(f.factor(A));
  const VecX b = ramp(15);
  EXPECT_LT((A * f.solve(b) - b).norm(), 1e-12 * b.norm());
  // A nonzero of B alone (A + B couples nodes 1 and 3; A does not).
  MatX B = MatX::Zero(15, 15);
  B(4, 10) = B(10, 4) = 0.9;
  B(5, 5) = 0.5;
  ASSERT_TRUE(f.factor(A, &B, 1.0));
  EXPECT_LT(((A + B) * f.solve(b) - b).norm(), 1e-12 * b.norm());
  MatXr X;
  f.half_solve(MatX::Identity(15, 15), X);  // XᵀX = (A + B)⁻¹
  EXPECT_LT((X.transpose() * X * (A + B) - MatX::Identity(15, 15)).norm(), 1e-11);
}

TEST(PatchCholesky, FactorsShareOnePatternAndKeepTheirOwnOrdering) {
  using contact_patch_detail::PatchPattern;
  const MatX A = chain(5, 0.7);
  const VecX b = ramp(15);
  PatchPattern pattern;
  PatchCholesky f, g;
  ASSERT_TRUE(f.factor(pattern, A));
  const MatX B = chain(5, 0.2) * 0.3;  // within the chain's pattern
  ASSERT_TRUE(g.factor(pattern, A, &B, -1.0));
  EXPECT_EQ(pattern.analyses(), 1);  // the second factor reused the first's analysis
  // g widens the shared pattern; f's factor, made on the old one, still solves A.
  MatX C = A;
  C(0, 13) = C(13, 0) = 1.5;
  ASSERT_TRUE(g.factor(pattern, C));
  EXPECT_EQ(pattern.analyses(), 2);
  EXPECT_LT((A * f.solve(b) - b).norm(), 1e-12 * b.norm());
  EXPECT_LT((C * g.solve(b) - b).norm(), 1e-12 * b.norm());
  ASSERT_TRUE(f.factor(pattern, A));  // on the widened pattern
  EXPECT_EQ(pattern.analyses(), 2);
  EXPECT_LT((A * f.solve(b) - b).norm(), 1e-12 * b.norm());
  // Another size starts over; a copied pattern is read again by its factors.
  const MatX small = chain(2, 0.3);
  PatchPattern copy = pattern;
  ASSERT_TRUE(f.factor(copy, A));
  EXPECT_LT((A * f.solve(b) - b).norm(), 1e-12 * b.norm());
  ASSERT_TRUE(f.factor(pattern, small));
  EXPECT_EQ(pattern.analyses(), 3);
  EXPECT_EQ(f.rows(), 6);
  EXPECT_LT((small * f.solve(ramp(6)) - ramp(6)).norm(), 1e-12 * ramp(6).norm());
}

TEST(PatchCholesky, HalfSolveGivesTheSchurComplement) {
  const MatX A = chain(4, 0.9);
  MatX C(12, 3);
  for (int i = 0; i < 12; ++i)
    for (int j = 0; j < 3; ++j) C(i, j) = std::sin(1.0 + i + 3.0 * j);
  PatchCholesky f;
  ASSERT_TRUE(f.factor(A));
  MatXr X(1, 1);  // storage of another shape: resized
  f.half_solve(C, X);
  const MatX expected = C.transpose() * A.llt().solve(C);  // dense, independent
  EXPECT_LT((X.transpose() * X - expected).norm(), 1e-12 * expected.norm());
}

TEST(PatchCholesky, AnIndefiniteMatrixIsReported) {
  MatX A = chain(3, 0.7);
  A(4, 4) = -2.0;
  PatchCholesky f;
  EXPECT_FALSE(f.factor(A));
  EXPECT_FALSE(f.ok());
  EXPECT_EQ(f.rows(), 0);
}

TEST(PatchCholesky, ACopyHoldsTheSameFactorAndMovesOnAlone) {
  const MatX A = chain(4, 0.6);
  PatchCholesky f;
  ASSERT_TRUE(f.factor(A));
  const PatchCholesky copy = f;
  const VecX b = ramp(12);
  EXPECT_EQ(copy.solve(b), f.solve(b));  // bit for bit: the same values factored again
  ASSERT_TRUE(f.factor(2.0 * A));
  EXPECT_LT((A * copy.solve(b) - b).norm(), 1e-12 * b.norm());
  EXPECT_LT((2.0 * A * f.solve(b) - b).norm(), 1e-12 * b.norm());
  PatchCholesky moved = std::move(f);
  EXPECT_LT((2.0 * A * moved.solve(b) - b).norm(), 1e-12 * b.norm());
}

}  // namespace
}  // namespace sflsh
