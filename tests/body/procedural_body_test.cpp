// The built-in procedural body: surface validity over the shape space,
// anthropometric plausibility, skinning weights, joint regressor, determinism.
#include "sflsh/body/procedural_body.hpp"

#include <gtest/gtest.h>

#include <random>

#include "sflsh/body/smpl_skeleton.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/meshing/surface_checks.hpp"

namespace sflsh {
namespace {

class ProceduralBody : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { model_ = new BodyModel(make_procedural_body()); }
  static void TearDownTestSuite() {
    delete model_;
    model_ = nullptr;
  }
  static const BodyModel& model() { return *model_; }
  static VecX betas(std::initializer_list<std::pair<int, double>> entries) {
    VecX b = VecX::Zero(model().num_betas());
    for (const auto& [i, v] : entries) b[i] = v;
    return b;
  }
  static BodyModel* model_;
};
BodyModel* ProceduralBody::model_ = nullptr;

double height_of(const Points& V) { return V.col(1).maxCoeff() - V.col(1).minCoeff(); }

TEST_F(ProceduralBody, TemplateIsAClosedGenusZeroBodyOfAdultHeight) {
  const BodyModel& m = model();
  EXPECT_NO_THROW(m.validate());
  EXPECT_GE(m.num_vertices(), 5000);
  EXPECT_LE(m.num_vertices(), 15000);
  const SurfaceReport r = check_surface(m.v_template, m.faces);
  EXPECT_TRUE(r.is_closed) << r.describe();
  EXPECT_TRUE(r.is_manifold) << r.describe();
  EXPECT_TRUE(r.consistently_oriented) << r.describe();
  EXPECT_EQ(r.num_components, 1);
  EXPECT_EQ(r.genus, 0);
  EXPECT_GT(r.signed_volume, 0.05);  // an adult: ~60-80 litres
  EXPECT_LT(r.signed_volume, 0.09);
  ASSERT_TRUE(r.self_intersection_tested);
  EXPECT_FALSE(r.self_intersects);
  EXPECT_GT(r.height(), 1.5);
  EXPECT_LT(r.height(), 2.0);
  EXPECT_NEAR(r.bbox_min.y(), 0.0, 0.01);  // standing on the floor
  EXPECT_GT(r.min_edge_length, 1e-3);      // no slivers left from the polygonization
  EXPECT_EQ(m.num_joints(), kSmplJoints);
  for (int j = 0; j < kSmplJoints; ++j) {
    EXPECT_EQ(m.parents[j], kSmplParents[j]);
    EXPECT_EQ(m.joint_names[j], kSmplJointNames[j]);
  }
  EXPECT_EQ(m.source, "procedural");
  // No pose blend shapes: stored empty so posing skips the 3V x 207 product.
  EXPECT_EQ(m.posedirs.size(), 0);
  EXPECT_FALSE(m.has_pose_blend_shapes());
  EXPECT_EQ(m.num_betas(), 10);
  ASSERT_EQ(int(m.shape_meanings.size()), m.num_betas());
  for (const auto& s : m.shape_meanings) EXPECT_FALSE(s.empty());
}

TEST_F(ProceduralBody, ProportionsAreAnthropometric) {
  const BodyModel& m = model();
  const double H = height_of(m.v_template);
  const double span = m.v_template.col(0).maxCoeff() - m.v_template.col(0).minCoeff();
  EXPECT_GT(span / H, 0.95);  // arm span ≈ stature (T-pose)
  EXPECT_LT(span / H, 1.10);
  const Points J = regress_joints(m, m.v_template);
  auto y = [&](const char* name) { return J(smpl_joint_index(name), 1) / H; };
  EXPECT_NEAR(y("left_knee"), 0.285, 0.02);  // Drillis & Contini
  EXPECT_NEAR(y("left_ankle"), 0.039, 0.01);
  EXPECT_NEAR(y("left_shoulder"), 0.80, 0.03);
  EXPECT_GT(y("pelvis"), y("left_hip"));
  EXPECT_GT(y("head"), y("neck"));
  EXPECT_GT(J(smpl_joint_index("left_wrist"), 0), 0.6);  // SMPL's left is +X
  EXPECT_LT(J(smpl_joint_index("right_wrist"), 0), -0.6);
  EXPECT_GT(J(smpl_joint_index("left_foot"), 2), J(smpl_joint_index("left_ankle"), 2) + 0.08);  // toes forward
}

TEST_F(ProceduralBody, WeightsArePartitionOfUnityAndLocal) {
  const BodyModel& m = model();
  ASSERT_EQ(m.weights.rows(), m.num_vertices());
  ASSERT_EQ(m.weights.cols(), kSmplJoints);
  EXPECT_GE(m.weights.minCoeff(), 0.0);
  EXPECT_LT((m.weights.rowwise().sum().array() - 1.0).abs().maxCoeff(), 1e-12);
  Eigen::Index top, left_tip, right_tip, toe;
  m.v_template.col(1).maxCoeff(&top);
  m.v_template.col(0).maxCoeff(&left_tip);
  m.v_template.col(0).minCoeff(&right_tip);
  m.v_template.col(2).maxCoeff(&toe);
  EXPECT_GT(m.weights(top, smpl_joint_index("head")), 0.9);
  EXPECT_GT(m.weights(left_tip, smpl_joint_index("left_hand")), 0.9);
  EXPECT_GT(m.weights(right_tip, smpl_joint_index("right_hand")), 0.9);
  const int foot = m.v_template(toe, 0) > 0 ? smpl_joint_index("left_foot") : smpl_joint_index("right_foot");
  EXPECT_GT(m.weights(toe, foot), 0.5);
  // Every joint, also the end joints, drives some part of the surface.
  for (int j = 0; j < kSmplJoints; ++j) EXPECT_GT(m.weights.col(j).maxCoeff(), 0.3) << kSmplJointNames[j];
  // Smooth: neighbouring vertices have similar weights.
  double max_jump = 0;
  for (int f = 0; f < m.faces.rows(); ++f)
    for (int c = 0; c < 3; ++c)
      max_jump = std::max(max_jump, (m.weights.row(m.faces(f, c)) - m.weights.row(m.faces(f, (c + 1) % 3)))
                                        .cwiseAbs()
                                        .maxCoeff());
  EXPECT_LT(max_jump, 0.25);
}

TEST_F(ProceduralBody, RegressorReproducesTheSkeletonAndMovesWithShape) {
  const BodyModel& m = model();
  ASSERT_EQ(m.J_regressor.rows(), kSmplJoints);
  ASSERT_EQ(m.J_regressor.cols(), m.num_vertices());
  const Points J = regress_joints(m, m.v_template);
  EXPECT_LT((J - procedural_body_joints(VecX())).rowwise().norm().maxCoeff(), 1e-9);
  for (int j = 0; j < kSmplJoints; ++j) {
    EXPECT_NEAR(m.J_regressor.row(j).sum(), 1.0, 1e-9);  // translation-equivariant
    EXPECT_GE(m.J_regressor.row(j).nonZeros(), 8);
  }
  // Shape changes: regressed joints follow the parametric skeleton.
  double worst = 0;
  for (int b = 0; b < m.num_betas(); ++b)
    for (double s : {-2.0, 2.0}) {
      const VecX beta = betas({{b, s}});
      const Points Jb = regress_joints(m, shape_vertices(m, beta));
      worst = std::max(worst, (Jb - procedural_body_joints(beta)).rowwise().norm().maxCoeff());
    }
  EXPECT_LT(worst, 0.015) << "metres";
  // Longer arms: the wrists move out; longer legs: the hips move up.
  const int wrist = smpl_joint_index("left_wrist"), hip = smpl_joint_index("left_hip");
  const Points J_arm = regress_joints(m, shape_vertices(m, betas({{6, 2.0}})));
  const Points J_leg = regress_joints(m, shape_vertices(m, betas({{7, 2.0}})));
  EXPECT_GT(J_arm(wrist, 0) - J(wrist, 0), 0.02);
  EXPECT_GT(J_leg(hip, 1) - J(hip, 1), 0.03);
}

TEST_F(ProceduralBody, JointsAreInsideTheBody) {
  const BodyModel& m = model();
  for (const VecX& beta : {VecX(VecX::Zero(m.num_betas())), VecX(VecX::Constant(m.num_betas(), -2.5)),
                           VecX(VecX::Constant(m.num_betas(), 2.5))}) {
    const Points V = shape_vertices(m, beta);
    const Points J = regress_joints(m, V);
    for (int j = 0; j < kSmplJoints; ++j)
      EXPECT_GT(winding_number(V, m.faces, J.row(j).transpose()), 0.5)
          << kSmplJointNames[j] << " at beta = " << beta.transpose();
  }
}

TEST_F(ProceduralBody, HeightIsMonotoneInBeta0) {
  const BodyModel& m = model();
  double previous = 0;
  for (double b0 = -3.0; b0 <= 3.0 + 1e-9; b0 += 0.5) {
    const double h = height_of(shape_vertices(m, betas({{0, b0}})));
    if (b0 > -3.0) {
      EXPECT_GT(h, previous + 0.02) << "beta0 = " << b0;
    }
    previous = h;
  }
  const double h_lo = height_of(shape_vertices(m, betas({{0, -3.0}})));
  const double h_hi = height_of(shape_vertices(m, betas({{0, 3.0}})));
  EXPECT_GT(h_hi - h_lo, 0.25);  // about ±17 cm
  EXPECT_LT(h_hi - h_lo, 0.45);
  // Girth makes the body heavier, not taller.
  const double v_thin = check_surface(shape_vertices(m, betas({{1, -2.0}})), m.faces, false).signed_volume;
  const double v_heavy = check_surface(shape_vertices(m, betas({{1, 2.0}})), m.faces, false).signed_volume;
  EXPECT_GT(v_heavy, 1.2 * v_thin);
}

TEST_F(ProceduralBody, ShapeSpaceKeepsTheSurfaceValid) {
  const BodyModel& m = model();
  const int B = m.num_betas();
  std::vector<VecX> samples = {VecX::Constant(B, 3.0), VecX::Constant(B, -3.0)};
  VecX alternating(B);
  for (int b = 0; b < B; ++b) alternating[b] = b % 2 ? 3.0 : -3.0;
  samples.push_back(alternating);
  samples.push_back(-alternating);
  std::mt19937 rng(2024);
  std::uniform_real_distribution<double> uniform(-3.0, 3.0);
  for (int k = 0; k < 10; ++k) {
    VecX beta(B);
    for (int b = 0; b < B; ++b) beta[b] = uniform(rng);
    samples.push_back(beta);
  }
  for (const VecX& beta : samples) {
    const Points V = shape_vertices(m, beta);
    const SurfaceReport r = check_surface(V, m.faces);
    EXPECT_TRUE(r.is_valid_body_surface()) << r.describe() << "\n  beta = " << beta.transpose();
    EXPECT_GT(r.height(), 1.4);
    EXPECT_LT(r.height(), 2.1);
  }
}

TEST_F(ProceduralBody, GenerationIsDeterministic) {
  const BodyModel again = make_procedural_body();
  const BodyModel& m = model();
  ASSERT_EQ(again.num_vertices(), m.num_vertices());
  EXPECT_TRUE(again.v_template == m.v_template);
  EXPECT_TRUE(again.faces == m.faces);
  EXPECT_TRUE(again.weights == m.weights);
  for (int b = 0; b < m.num_betas(); ++b) EXPECT_TRUE(again.shapedirs[b] == m.shapedirs[b]);
  EXPECT_EQ((again.J_regressor - m.J_regressor).norm(), 0.0);
}

TEST(ProceduralBodyOptions, ResolutionAndShapeCountFollowTheOptions) {
  ProceduralBodyOptions options;
  options.target_vertices = 6000;
  options.num_betas = 8;
  const BodyModel m = make_procedural_body(options);
  EXPECT_GT(m.num_vertices(), 5000);
  EXPECT_LT(m.num_vertices(), 7000);
  EXPECT_EQ(m.num_betas(), 8);
  EXPECT_EQ(m.shape_meanings.size(), 8u);
  EXPECT_TRUE(check_surface(m.v_template, m.faces).is_valid_body_surface());
  options.num_betas = 3;
  EXPECT_THROW(make_procedural_body(options), Error);
  options.num_betas = 10;
  options.target_vertices = 10;
  EXPECT_THROW(make_procedural_body(options), Error);
  EXPECT_THROW(procedural_body_joints(VecX::Zero(11)), Error);
}

}  // namespace
}  // namespace sflsh
