// joint_carried_inertia (skeleton_terms.hpp): the rotational inertia about
// each joint of the flesh and bones its rotation moves, checked against the
// kinetic energy of actually turning the subtree's bones (brute force through
// the skinned cubature points), and the springs it sizes.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include "sflsh/core/rotation.hpp"
#include "sflsh/sim/energies/inertia.hpp"
#include "sflsh/sim/posed_points.hpp"
#include "sflsh/sim/skeleton_terms.hpp"
#include "skeleton_fixture.hpp"
#include "synthetic_avatar.hpp"

namespace sflsh {
namespace {

/// Synthetic box (flesh skinned to bones 0, 3 and 6) on the T-pose skeleton.
Avatar carried_avatar() {
  Avatar a = test::make_synthetic_avatar();
  a.joints_rest = test::make_tpose_skeleton().joints_rest;
  return a;
}

/// Σ_s m_s |Δx_s|² / ε² when joint j's subtree turns by ε about `axis`
/// through the joint: aᵀ I_j a of the flesh, from the skinned positions.
double turned_subtree_energy(const Avatar& a, int j, const Vec3& axis) {
  const double eps = 1e-5;
  const PosedPoints pts = PosedPoints::at_cubature(a, a.inertia);
  const VecX m = cubature_masses(a, a.inertia);
  Configuration rest, turned;
  rest.bones.assign(24, Isometry::Identity());
  rest.z = turned.z = VecX::Zero(a.num_reduced());
  turned.bones = rest.bones;
  const Vec3 p = a.joints_rest.row(j).transpose();
  Isometry T = Isometry::Identity();
  T.linear() = rodrigues(eps * axis);
  T.translation() = p - T.linear() * p;  // about the joint
  for (int b = 0; b < 24; ++b)
    for (int k = b; k >= 0; k = a.parents[k])
      if (k == j) turned.bones[b] = T;
  const Points d = pts.world(turned) - pts.world(rest);
  double e = 0;
  for (int s = 0; s < pts.size(); ++s) e += m[s] * d.row(s).squaredNorm();
  return e / (eps * eps);
}

TEST(CarriedInertia, MatchesTheKineticEnergyOfTurningTheSubtree) {
  const Avatar a = carried_avatar();
  ASSERT_GT(a.inertia.size(), 0);
  // Skeleton of negligible mass: the flesh alone.
  std::vector<BoneBody> light(24);
  for (BoneBody& b : light) b.mass = 1e-12;
  const std::vector<double> I = joint_carried_inertia(a, light);
  for (int j : {0, 3, 6}) {
    // The tensor from six turns (polarization), its largest eigenvalue.
    Mat3 T;
    const Vec3 e[3] = {Vec3::UnitX(), Vec3::UnitY(), Vec3::UnitZ()};
    for (int r = 0; r < 3; ++r) T(r, r) = turned_subtree_energy(a, j, e[r]);
    for (int r = 0; r < 3; ++r)
      for (int c = r + 1; c < 3; ++c)
        T(r, c) = T(c, r) =
            0.5 * (turned_subtree_energy(a, j, (e[r] + e[c]).normalized()) * 2 - T(r, r) - T(c, c));
    const double expected = Eigen::SelfAdjointEigenSolver<Mat3>(T).eigenvalues()(2);
    ASSERT_GT(expected, 0.0) << j;
    EXPECT_NEAR(I[j], expected, 1e-4 * expected) << "joint " << j;
  }
  // Joints whose subtree carries no flesh (the arms of this box): no inertia.
  EXPECT_LT(I[18], 1e-9);
}

TEST(CarriedInertia, AddsTheSkeletonAndSizesTheSprings) {
  const Avatar a = carried_avatar();
  const std::vector<BoneBody> skeleton = bone_bodies(a, 10.0);
  std::vector<BoneBody> light(24);
  for (BoneBody& b : light) b.mass = 1e-12;
  const std::vector<double> flesh = joint_carried_inertia(a, light), both = joint_carried_inertia(a, skeleton);
  const std::vector<double> bones = joint_subtree_inertia(a, skeleton);
  for (int j = 0; j < 24; ++j) {
    // Largest eigenvalue of a sum of PSD tensors: between the larger part and the sum.
    EXPECT_GE(both[j], std::max(flesh[j], bones[j]) * (1 - 1e-12)) << j;
    EXPECT_LE(both[j], (flesh[j] + bones[j]) * (1 + 1e-12)) << j;
  }
  Avatar none = a;
  none.inertia = Cubature();
  EXPECT_THROW(joint_carried_inertia(none, skeleton), Error);
  EXPECT_THROW(joint_carried_inertia(a, std::vector<BoneBody>(3)), Error);
}

}  // namespace
}  // namespace sflsh
