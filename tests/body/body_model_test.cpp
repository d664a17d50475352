// SMPL forward function: hand-computed LBS on a toy, the numpy reference of
// data_tools/smpl_reference.py (committed fixtures), model validation, presets
// and β parsing.
#include "sflsh/body/body_model.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "sflsh/body/body_model_io.hpp"
#include "sflsh/body/smpl_skeleton.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/io/npz.hpp"
#include "test_support.hpp"

namespace sflsh {
namespace {

constexpr double kPi = 3.14159265358979323846;

using test::generated_fixture;

using test::expect_error;

// A 24-joint model whose first 24 vertices sit at the joints `J` (weight 1 to
// their own joint, regressor = identity on them), plus `extra` vertices with
// the given weights. SMPL's tree; no shape or pose blend shapes.
BodyModel stick_model(const Points& J, const Points& extra = Points(0, 3), const MatXr& extra_w = MatXr(0, 24)) {
  const int V = kSmplJoints + int(extra.rows());
  BodyModel m;
  m.source = "stick";
  m.v_template.resize(V, 3);
  m.v_template.topRows(kSmplJoints) = J;
  m.v_template.bottomRows(extra.rows()) = extra;
  m.faces.resize(1, 3);
  m.faces << 0, 1, 2;
  m.posedirs = MatX::Zero(3 * V, kSmplPoseFeatures);
  m.weights = MatXr::Zero(V, kSmplJoints);
  m.weights.topRows(kSmplJoints).setIdentity();
  m.weights.bottomRows(extra.rows()) = extra_w;
  m.J_regressor.resize(kSmplJoints, V);
  for (int j = 0; j < kSmplJoints; ++j) m.J_regressor.insert(j, j) = 1.0;
  m.J_regressor.makeCompressed();
  m.parents.assign(kSmplParents.begin(), kSmplParents.end());
  for (auto n : kSmplJointNames) m.joint_names.emplace_back(n);
  return m;
}

// Joints at the origin except joint 1 (left_hip) at (1, 0, 0): a two-bone toy.
Points toy_joints() {
  Points J = Points::Zero(kSmplJoints, 3);
  J.row(1) << 1, 0, 0;
  for (int j = 4; j < kSmplJoints; ++j) J.row(j) << 0, -1, 0;  // keep others apart from the toy bones
  return J;
}

TEST(BodyModel, HandComputedLinearBlendSkinning) {
  // Vertex a at (2, 0, 0) follows joint 1 only; vertex b at (1.5, 0, 0) is half
  // joint 0, half joint 1. Rotating joint 1 by 90° about +Z maps (x, y) around
  // the joint at (1, 0): a -> (1, 1); b -> joint 0 keeps (1.5, 0), joint 1 gives
  // (1, 0.5); the blend is (1.25, 0.25).
  Points extra(2, 3);
  extra << 2, 0, 0, 1.5, 0, 0;
  MatXr w = MatXr::Zero(2, kSmplJoints);
  w(0, 1) = 1.0;
  w(1, 0) = 0.5;
  w(1, 1) = 0.5;
  BodyModel m = stick_model(toy_joints(), extra, w);
  ASSERT_NO_THROW(m.validate());
  BodyPose pose;
  pose.axis_angle.row(1) << 0, 0, kPi / 2;
  pose.translation << 0.5, 0, -1;
  const PosedBody r = pose_body(m, VecX(), pose);
  const int a = kSmplJoints, b = kSmplJoints + 1;
  EXPECT_NEAR((r.v_posed.row(a) - Eigen::RowVector3d(1.5, 1, -1)).norm(), 0, 1e-12) << r.v_posed.row(a);
  EXPECT_NEAR((r.v_posed.row(b) - Eigen::RowVector3d(1.75, 0.25, -1)).norm(), 0, 1e-12) << r.v_posed.row(b);
  // The rotated joint itself does not move; the translation moves everything.
  EXPECT_NEAR((r.joints_posed.row(1) - Eigen::RowVector3d(1.5, 0, -1)).norm(), 0, 1e-12);
  EXPECT_NEAR((r.joints_posed.row(0) - Eigen::RowVector3d(0.5, 0, -1)).norm(), 0, 1e-12);

  // Pose blend shapes: the feature of joint 1 is vec(Rz(90°) - I) =
  // (-1, -1, 0, 1, -1, 0, 0, 0, 0). A pose direction moving vertex a by +0.1 in
  // y per unit of feature entry 3 shifts its unposed position by (0, 0.1, 0),
  // which the 90° rotation turns into (-0.1, 0, 0) in world.
  const VecX feat = pose_feature(pose.axis_angle);
  const double want[9] = {-1, -1, 0, 1, -1, 0, 0, 0, 0};
  for (int k = 0; k < 9; ++k) EXPECT_NEAR(feat[k], want[k], 1e-15) << k;
  for (int k = 9; k < kSmplPoseFeatures; ++k) EXPECT_EQ(feat[k], 0.0) << k;
  m.posedirs(3 * a + 1, 3) = 0.1;
  ASSERT_TRUE(m.has_pose_blend_shapes());
  const PosedBody rp = pose_body(m, VecX(), pose);
  EXPECT_NEAR((rp.v_posed.row(a) - Eigen::RowVector3d(1.4, 1, -1)).norm(), 0, 1e-12) << rp.v_posed.row(a);
}

TEST(BodyModel, ShapeBlendShapesMoveRegressedJoints) {
  BodyModel m = stick_model(toy_joints());
  m.shapedirs.assign(2, Points::Zero(m.num_vertices(), 3));
  m.shapedirs[0].row(1) << 0, 0.5, 0;  // β0 lifts joint 1's vertex
  m.shapedirs[1].setConstant(0.25);    // β1 shifts everything
  VecX betas(2);
  betas << 2.0, -1.0;
  const PosedBody r = pose_body(m, betas, BodyPose());
  EXPECT_NEAR((r.joints_rest.row(1) - Eigen::RowVector3d(0.75, 0.75, -0.25)).norm(), 0, 1e-12);
  EXPECT_NEAR((r.v_posed - r.v_shaped).norm(), 0, 1e-12);  // zero pose: LBS is the identity
  // Fewer betas than directions is allowed, more is an error naming both counts.
  EXPECT_NO_THROW(shape_vertices(m, VecX::Ones(1)));
  expect_error([&] { shape_vertices(m, VecX::Ones(3)); }, {"3 values", "2 shape directions"});
}

// The committed numpy reference (data_tools/smpl_reference.py) on a random
// float32 SMPL-format model with non-zero pose directions and a sparse regressor.
TEST(BodyModel, MatchesNumpyReference) {
  const BodyModel m = read_body_model_npz(generated_fixture("tiny_smpl.npz"));
  ASSERT_TRUE(m.has_pose_blend_shapes());
  const auto expected = io::read_npz(generated_fixture("tiny_smpl_expected.npz"));
  const int cases = int(expected.at("num_cases").data.at(0));
  ASSERT_EQ(cases, 3);
  auto points = [&](const std::string& key) {
    const io::NpyArray& a = expected.at(key);
    return Points(Eigen::Map<const Points>(a.data.data(), a.shape.at(0), 3));
  };
  for (int c = 0; c < cases; ++c) {
    const std::string p = "case" + std::to_string(c) + "_";
    const io::NpyArray& b = expected.at(p + "betas");
    BodyPose pose;
    pose.axis_angle = points(p + "pose");
    pose.translation = Eigen::Map<const Vec3>(expected.at(p + "trans").data.data());
    const PosedBody r = pose_body(m, Eigen::Map<const VecX>(b.data.data(), Eigen::Index(b.data.size())), pose);
    for (const auto& [key, got] : {std::pair<std::string, const Points*>{"v_shaped", &r.v_shaped},
                                   {"joints_rest", &r.joints_rest},
                                   {"v_posed", &r.v_posed},
                                   {"joints_posed", &r.joints_posed}}) {
      const Points want = points(p + key);
      ASSERT_EQ(got->rows(), want.rows()) << p << key;
      EXPECT_LT((*got - want).cwiseAbs().maxCoeff(), 1e-9) << p << key;
    }
    // Posing moved the vertices (not a trivial pass-through) in the posed cases.
    if (c > 0) {
      EXPECT_GT((r.v_posed - r.v_shaped).norm(), 0.1) << p;
    }
  }
}

TEST(BodyModel, JointTransformsMapRestJointsAndRigidVertices) {
  const BodyModel m = read_body_model_npz(generated_fixture("tiny_smpl.npz"));
  std::mt19937 rng(3);
  std::normal_distribution<double> n(0.0, 0.6);
  BodyPose pose;
  for (int j = 0; j < kSmplJoints; ++j) pose.axis_angle.row(j) << n(rng), n(rng), n(rng);
  pose.translation << 0.3, -0.1, 2.0;
  const PosedBody r = pose_body(m, VecX::Zero(2), pose);
  ASSERT_EQ(r.joint_transforms.size(), size_t(kSmplJoints));
  for (int j = 0; j < kSmplJoints; ++j) {
    const Eigen::Matrix4d& G = r.joint_transforms[j];
    const Vec3 x = G.topLeftCorner<3, 3>() * r.joints_rest.row(j).transpose() + G.topRightCorner<3, 1>();
    EXPECT_LT((x.transpose() - r.joints_posed.row(j)).norm(), 1e-12) << j;
    EXPECT_LT((G.topLeftCorner<3, 3>().transpose() * G.topLeftCorner<3, 3>() - Mat3::Identity()).norm(), 1e-12);
    EXPECT_EQ(G.row(3), Eigen::RowVector4d(0, 0, 0, 1));
  }
  // Bone lengths are preserved by posing.
  for (int j = 1; j < kSmplJoints; ++j) {
    const int p = m.parents[j];
    EXPECT_NEAR((r.joints_posed.row(j) - r.joints_posed.row(p)).norm(),
                (r.joints_rest.row(j) - r.joints_rest.row(p)).norm(), 1e-12);
  }
}

TEST(BodyModel, ValidateNamesTheOffendingArray) {
  const BodyModel good = read_body_model_npz(generated_fixture("tiny_smpl.npz"));
  ASSERT_NO_THROW(good.validate());
  auto broken = [&](auto edit, std::initializer_list<std::string> fragments) {
    BodyModel m = good;
    edit(m);
    expect_error([&] { m.validate(); }, fragments);
  };
  broken([](BodyModel& m) { m.faces(3, 1) = 20; }, {"f[3, 1]", "[0, 20)"});
  broken([](BodyModel& m) { m.faces(0, 0) = -1; }, {"f[0, 0]"});
  broken([](BodyModel& m) { m.weights(5, 0) += 0.01; }, {"weights row 5", "expected 1"});
  broken([](BodyModel& m) { m.weights(2, 3) = -0.5; m.weights(2, 4) += 0.5; }, {"weights[2, 3]", ">= 0"});
  broken([](BodyModel& m) { m.weights(1, 1) = std::nan(""); }, {"weights[1, 1]"});
  broken([](BodyModel& m) { m.parents[7] = 9; }, {"parent of joint 7", "[0, 7)"});
  broken([](BodyModel& m) { m.parents.pop_back(); }, {"23 joints", "(2, 24)"});
  broken([](BodyModel& m) { m.J_regressor.resize(24, 19); }, {"J_regressor", "(24, 20)"});
  broken([](BodyModel& m) { m.posedirs.resize(60, 200); }, {"posedirs", "60 by 207"});
  broken([](BodyModel& m) { m.shapedirs[1].resize(19, 3); }, {"shapedirs direction 1", "(20, 3, B)"});
  broken([](BodyModel& m) { m.v_template(4, 2) = INFINITY; }, {"v_template", "non-finite"});
  broken([](BodyModel& m) { m.joint_names.resize(3); }, {"joint_names", "expected 24"});
}

TEST(BodyModel, PosePresetsBendTheSkeletonAsNamed) {
  // SMPL-like rest joints (metres, T-pose, facing +Z, left = +X).
  Points J(kSmplJoints, 3);
  J << 0, 0.92, 0,  0.08, 0.85, 0,  -0.08, 0.85, 0,  0, 1.02, 0,  0.09, 0.47, 0,  -0.09, 0.47, 0,
      0, 1.15, 0,  0.09, 0.07, 0,  -0.09, 0.07, 0,  0, 1.20, 0,  0.10, 0.02, 0.12,  -0.10, 0.02, 0.12,
      0, 1.42, 0,  0.08, 1.35, 0,  -0.08, 1.35, 0,  0, 1.55, 0,  0.18, 1.38, 0,  -0.18, 1.38, 0,
      0.45, 1.38, 0,  -0.45, 1.38, 0,  0.70, 1.38, 0,  -0.70, 1.38, 0,  0.78, 1.38, 0,  -0.78, 1.38, 0;
  const BodyModel m = stick_model(J);
  auto joint = [](const PosedBody& r, const char* name) -> Vec3 {
    return r.joints_posed.row(smpl_joint_index(name)).transpose();
  };

  const PosedBody t = pose_body(m, VecX(), pose_preset("tpose"));
  EXPECT_LT((t.joints_posed - J).norm(), 1e-12);

  const PosedBody a = pose_body(m, VecX(), pose_preset("apose"));
  for (const char* side : {"left", "right"}) {
    const Vec3 arm = joint(a, (std::string(side) + "_wrist").c_str()) - joint(a, (std::string(side) + "_shoulder").c_str());
    const double below = std::atan2(-arm.y(), std::abs(arm.x())) * 180 / kPi;
    EXPECT_NEAR(below, 45.0, 1.0) << side;
    EXPECT_NEAR(arm.z(), 0.0, 1e-9) << side;
  }

  const PosedBody w = pose_body(m, VecX(), pose_preset("walk"));
  EXPECT_GT(joint(w, "left_ankle").z(), 0.1);   // leading foot forward
  EXPECT_LT(joint(w, "right_ankle").z(), -0.05);  // trailing foot behind
  EXPECT_LT(joint(w, "left_wrist").y(), joint(w, "left_shoulder").y() - 0.3);  // arms down

  const PosedBody s = pose_body(m, VecX(), pose_preset("sit"));
  for (const char* side : {"left", "right"}) {
    const std::string sd(side);
    const Vec3 hip = joint(s, (sd + "_hip").c_str()), knee = joint(s, (sd + "_knee").c_str()),
               ankle = joint(s, (sd + "_ankle").c_str());
    EXPECT_NEAR(knee.y(), hip.y(), 1e-9) << side;   // thigh horizontal
    EXPECT_NEAR(knee.z() - hip.z(), 0.38, 1e-9) << side;  // pointing forward, full thigh length
    EXPECT_NEAR(ankle.z(), knee.z(), 1e-9) << side;  // shank vertical
    EXPECT_LT(ankle.y(), knee.y() - 0.3) << side;
  }

  expect_error([] { pose_preset("dab"); }, {"'dab'", "apose", "sit", "tpose", "walk"});
}

TEST(BodyModel, ParseBetas) {
  const VecX b = parse_betas("0.5,-1, 2");
  ASSERT_EQ(b.size(), 3);
  EXPECT_EQ(b[0], 0.5);
  EXPECT_EQ(b[1], -1.0);
  EXPECT_EQ(b[2], 2.0);
  EXPECT_EQ(parse_betas("").size(), 0);
  EXPECT_EQ(parse_betas("1e-2")[0], 0.01);
  expect_error([] { parse_betas("0.5,x,2"); }, {"token 2", "'x'"});
  expect_error([] { parse_betas("1,,2"); }, {"token 2", "''"});
  expect_error([] { parse_betas("1.5abc"); }, {"'1.5abc'"});
  expect_error([] { parse_betas("nan"); }, {"'nan'"});
}

// The forward function on a 10k-vertex model with 4 bones per vertex and no
// pose blend shapes (the procedural body's case): posedirs empty (as the
// readers store all-zero ones) poses exactly as a dense all-zero matrix. (Its
// speed is a benchmark figure, not a test: DESIGN.md §6.)
TEST(BodyModel, EmptyPosedirsPoseLikeAllZeroPosedirs) {
  const int V = 10000;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Points extra(V - kSmplJoints, 3);
  MatXr w = MatXr::Zero(V - kSmplJoints, kSmplJoints);
  for (int v = 0; v < extra.rows(); ++v) {
    extra.row(v) << u(rng), u(rng), u(rng);
    for (int k = 0; k < 4; ++k) w(v, rng() % kSmplJoints) += 0.25;
  }
  BodyModel m = stick_model(toy_joints(), extra, w);
  m.shapedirs.assign(10, Points::Constant(V, 3, 0.01));
  const BodyPose pose = pose_preset("walk");
  const VecX betas = VecX::Constant(10, 0.5);
  const PosedBody dense = pose_body(m, betas, pose);
  m.posedirs = MatX();
  ASSERT_NO_THROW(m.validate());
  EXPECT_FALSE(m.has_pose_blend_shapes());
  const PosedBody empty = pose_body(m, betas, pose);
  EXPECT_EQ(empty.v_posed, dense.v_posed);
  // The pose moved the vertices: the comparison is not of two rest shapes.
  EXPECT_GT((empty.v_posed - pose_body(m, betas, pose_preset("tpose")).v_posed).cwiseAbs().maxCoeff(), 1e-3);
}

}  // namespace
}  // namespace sflsh
