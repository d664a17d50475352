#include "sflsh/basis/stiffness_fitted_cubature.hpp"

#include <gtest/gtest.h>

#include "box_mesh.hpp"
#include "sflsh/basis/bounded_biharmonic.hpp"
#include "sflsh/basis/cubature.hpp"
#include "sflsh/basis/handle_placement.hpp"
#include "sflsh/core/error.hpp"

namespace sflsh::basis {
namespace {

struct Box {
  TetMesh mesh = test::box_tet_mesh(10, 4, 6, 0.3, 0.1, 0.2);
  VecXi role;
  Eigen::SparseMatrix<double, Eigen::RowMajor> W;
  explicit Box(int K) {
    role = VecXi::Zero(mesh.num_nodes());
    for (int i = 0; i < mesh.num_nodes(); ++i)
      if (mesh.nodes(i, 1) < 1e-12) role(i) = int(NodeRole::Bone);
    BbwOptions o;
    o.show_progress = false;
    W = bounded_biharmonic_weights(mesh, role, select_handles(mesh, role, K).nodes, o);
  }
};

TEST(StiffnessFittedCubature, EveryTetAsCandidateReproducesTheStiffnessTensor) {
  const Box b(6);
  // With all tets (weights = volumes) the tensor is matched exactly from the start.
  const Cubature all = full_cubature(b.mesh);
  FittedCubatureReport r;
  const Cubature fit = stiffness_fitted_cubature(b.mesh, b.W, b.role, all, VecX(), &r);
  EXPECT_LT(r.stiffness_error_initial, 1e-12);
  EXPECT_LT(r.stiffness_error, 1e-9);
  EXPECT_LT(std::abs(r.volume_error), 1e-9);
  EXPECT_EQ(r.candidates, all.size());
  EXPECT_EQ(fit.size(), r.samples);
}

TEST(StiffnessFittedCubature, FitLowersTheErrorOfTheStratifiedSamplesWithNonNegativeWeights) {
  const Box b(8);
  const Cubature strat = stratified_cubature(b.mesh, b.W, VecXi(), 3);
  VecX modulus = VecX::Ones(b.mesh.num_elements());
  for (int t = 0; t < modulus.size(); ++t)
    if (b.mesh.nodes(b.mesh.elements(t, 0), 0) > 0.15) modulus[t] = 4.0;  // two materials
  FittedCubatureReport r;
  const Cubature fit = stiffness_fitted_cubature(b.mesh, b.W, b.role, strat, modulus, &r);
  std::printf("stiffness-tensor error: %.3f -> %.3f with %d of %d samples\n", r.stiffness_error_initial,
              r.stiffness_error, r.samples, r.candidates);
  EXPECT_LT(r.stiffness_error, 0.8 * r.stiffness_error_initial);  // measured 0.655 -> 0.428
  EXPECT_GT(fit.weights.minCoeff(), 0.0);
  EXPECT_LE(fit.size(), strat.size());
  for (int s = 0; s < fit.size(); ++s) {
    bool found = false;
    for (int c = 0; c < strat.size(); ++c) found |= strat.elements[c] == fit.elements[s];
    EXPECT_TRUE(found) << "sample " << s << " is not a candidate";
  }
  EXPECT_THROW(stiffness_fitted_cubature(b.mesh, b.W, b.role, strat, VecX::Ones(3)), sflsh::Error);
}

}  // namespace
}  // namespace sflsh::basis
