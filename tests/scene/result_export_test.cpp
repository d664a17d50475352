// Exports and renders of scenes with rigid objects, on a hand-made result:
// two bodies (upright strips at x ∈ ±[0.8, 1], y ∈ [0, 2], facing +Z), a
// ball between them moving and turning about +Y, a tilted floor plane behind
// them stored as a huge patch, and a turned crate.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "io/glb_dump.hpp"
#include "sflsh/geometry/primitive_meshes.hpp"
#include "sflsh/io/mesh_export.hpp"
#include "sflsh/io/png_image.hpp"
#include "sflsh/io/point_cache.hpp"
#include "sflsh/scene/result_export.hpp"
#include "test_support.hpp"

namespace sflsh {
namespace {

constexpr double kBallRadius = 0.3;
const Vec3 kFloorNormal = Vec3(0, 1, 0.3).normalized();

Isometry turn_about_y(double angle, const Vec3& t) {
  Isometry T = Isometry::Identity();
  T.linear() = Eigen::AngleAxisd(angle, Vec3::UnitY()).toRotationMatrix();
  T.translation() = t;
  return T;
}

/// Frame k: the ball at (0.1k, 1, 0.2k) turned by 0.5k about +Y.
Vec3 ball_translation(int k) { return Vec3(0.1 * k, 1.0, 0.2 * k); }

SimulationResult scene(bool with_crate, int num_frames = 3) {
  SimulationResult r;
  r.motion = "scene:test";
  r.body_names = {"left", "right"};
  r.body_vertex_offsets = {0, 4, 8};
  r.faces.resize(4, 3);
  r.faces << 0, 1, 2, 0, 2, 3, 4, 5, 6, 4, 6, 7;
  Points strips(8, 3);
  strips << -1, 0, 0, -0.8, 0, 0, -0.8, 2, 0, -1, 2, 0,  //
      0.8, 0, 0, 1, 0, 0, 1, 2, 0, 0.8, 2, 0;
  r.surface_rest = strips;
  ObjectTrack ball{"ball", "sphere", "kinematic", Points(), Triangles(), {}};
  const geometry::PrimitiveMesh sphere = geometry::sphere_mesh(kBallRadius, 16);
  ball.vertices = sphere.vertices;
  ball.faces = sphere.faces;
  const geometry::PrimitiveMesh huge = geometry::plane_patch_mesh(kFloorNormal, 0.0, 1000.0);
  ObjectTrack floor{"floor", "plane", "static", huge.vertices, huge.faces, {}};
  const geometry::PrimitiveMesh box = geometry::box_mesh(Vec3(0.2, 0.1, 0.3));
  ObjectTrack crate{"crate", "box", "static", box.vertices, box.faces, {}};
  for (int k = 0; k < num_frames; ++k) {
    r.frame_time.push_back(k / 10.0);
    r.frame_step_ms.push_back(1.0);
    r.frame_positions.push_back(strips);
    r.frame_displacement.push_back(Points::Zero(8, 3));
    r.frame_joints.push_back(Points::Zero(48, 3));
    r.frame_reduced.push_back(VecX::Zero(2));
    ball.poses.push_back(turn_about_y(0.5 * k, ball_translation(k)));
    floor.poses.push_back(Isometry::Identity());
    crate.poses.push_back(turn_about_y(1.0, Vec3(0, 0.5, 0.4)));
  }
  r.objects = {ball, floor};
  if (with_crate) r.objects.push_back(crate);
  r.num_frames = num_frames;
  return r;
}

TEST(ResultExport, GlbHasANodePerObjectAnimatedByItsPoses) {
  test::TempDir tmp;
  const SimulationResult r = scene(true);
  const std::string line = export_result(r, tmp.file("s.glb"));
  EXPECT_NE(line.find("3 rigid object node(s)"), std::string::npos) << line;
  const test::GlbDump d = test::dump_glb(tmp.file("s.glb"));
  ASSERT_EQ(d.nodes.size(), 4u);  // the skin + 3 objects
  EXPECT_EQ(d.nodes[0].name, "body");
  EXPECT_EQ(d.nodes[1].name, "ball");
  EXPECT_EQ(d.nodes[2].name, "floor");
  EXPECT_EQ(d.nodes[3].name, "crate");
  EXPECT_EQ(d.scene_nodes, (std::vector<int>{0, 1, 2, 3}));
  EXPECT_EQ(d.mesh_vertices[0], 8);
  EXPECT_EQ(d.mesh_vertices[2], 4);   // the floor as one square patch
  EXPECT_EQ(d.mesh_vertices[3], 24);  // the crate's corners split per side for flat shading
  EXPECT_EQ(d.material_double_sided, (std::vector<bool>{false, false, true, false}));
  EXPECT_EQ(d.material_color[1], (std::vector<double>{0.6, 0.6, 0.6, 1}));
  // Morph weights for the skin, translation + rotation for the moving ball
  // only: the floor and the crate stand still.
  ASSERT_EQ(d.channels.size(), 3u);
  EXPECT_NE(d.channel(0, "weights"), nullptr);
  const auto* t = d.channel(1, "translation");
  const auto* q = d.channel(1, "rotation");
  ASSERT_TRUE(t && q);
  ASSERT_EQ(t->values.size(), 3u);
  for (int k = 0; k < 3; ++k) {
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(t->values[size_t(k)][size_t(c)], ball_translation(k)[c], 1e-6) << k;
    // A turn by θ = 0.5k about +Y: (x, y, z, w) = (0, sin θ/2, 0, cos θ/2).
    const double expected[4] = {0, std::sin(0.25 * k), 0, std::cos(0.25 * k)};
    for (int c = 0; c < 4; ++c) EXPECT_NEAR(q->values[size_t(k)][size_t(c)], expected[c], 1e-6) << k;
  }
  // The crate's still pose on its node: turned by 1 rad about +Y.
  ASSERT_EQ(d.nodes[3].rotation.size(), 4u);
  EXPECT_NEAR(d.nodes[3].rotation[1], std::sin(0.5), 1e-8);
  EXPECT_NEAR(d.nodes[3].rotation[3], std::cos(0.5), 1e-8);
  EXPECT_NEAR(d.nodes[3].translation[2], 0.4, 1e-8);
}

TEST(ResultExport, CacheAndMeshSequenceMergeThePosedObjects) {
  test::TempDir tmp;
  const SimulationResult r = scene(false);
  const std::string line = export_result(r, tmp.file("s.pc2"));
  EXPECT_NE(line.find("2 rigid object(s) merged after the skin's 8 vertices"), std::string::npos) << line;
  const io::PointCache pc = io::read_pc2(tmp.file("s.pc2"));
  const Eigen::Index nb = r.objects[0].vertices.rows();
  ASSERT_EQ(pc.frames.size(), 3u);
  ASSERT_EQ(pc.frames[0].rows(), 8 + nb + 4);
  // The ball's vertex at local (r, 0, 0), turned by θ = 0.5k about +Y, is at
  // (r cos θ, 0, −r sin θ) + t_k; its bottom pole at t_k − (0, r, 0).
  Eigen::Index side = 0, pole = 0;
  (r.objects[0].vertices.rowwise() - Vec3(kBallRadius, 0, 0).transpose()).rowwise().norm().minCoeff(&side);
  (r.objects[0].vertices.rowwise() - Vec3(0, -kBallRadius, 0).transpose()).rowwise().norm().minCoeff(&pole);
  for (int k = 0; k < 3; ++k) {
    const Points& P = pc.frames[size_t(k)];
    EXPECT_LT((P.topRows(8) - r.frame_positions[0]).cwiseAbs().maxCoeff(), 1e-6);
    const Vec3 side_expected = ball_translation(k) + kBallRadius * Vec3(std::cos(0.5 * k), 0, -std::sin(0.5 * k));
    EXPECT_LT((P.row(8 + side).transpose() - side_expected).norm(), 1e-6) << k;
    EXPECT_LT((P.row(8 + pole).transpose() - (ball_translation(k) - Vec3(0, kBallRadius, 0))).norm(), 1e-6) << k;
    // The floor: a patch in its plane, centred under the bodies and larger
    // than them, not the stored 2 km one.
    const Points patch = P.bottomRows(4);
    EXPECT_LT((patch * kFloorNormal).cwiseAbs().maxCoeff(), 1e-5);
    EXPECT_LT(patch.col(0).minCoeff(), -1.2);
    EXPECT_GT(patch.col(0).maxCoeff(), 1.2);
    EXPECT_LT(patch.cwiseAbs().maxCoeff(), 6.0);
  }
  const io::ImportedMesh rest = io::read_mesh(tmp.file("s_rest.obj"));
  EXPECT_EQ(rest.faces.rows(), 4 + r.objects[0].faces.rows() + 2);

  const std::string seq = export_result(r, tmp.file("f_%02d.obj"));
  EXPECT_NE(seq.find("merged"), std::string::npos) << seq;
  const io::ImportedMesh f2 = io::read_mesh(tmp.file("f_02.obj"));
  EXPECT_EQ(f2.faces.rows(), 4 + r.objects[0].faces.rows() + 2);
  // The ball's top at frame 2: t_2 + (0, r, 0) = (0.2, 1.3, 0.4).
  EXPECT_LT((f2.vertices.rowwise() - Vec3(0.2, 1.0 + kBallRadius, 0.4).transpose()).rowwise().norm().minCoeff(), 1e-6);
}

/// The coloured skin's pixel box in the first panel, as [x0, x1] × [y0, y1]:
/// columns holding non-grey pixels come in runs (left strip, right strip,
/// then the colour bar); the box spans the first two.
struct PixelBox {
  int x0 = 1 << 30, x1 = -1, y0 = 1 << 30, y1 = -1;
};
bool greyish(io::Rgb8 c) { return std::abs(c[0] - c[1]) < 8 && std::abs(c[1] - c[2]) < 8; }
PixelBox skin_box(const io::Image& img) {
  std::vector<int> runs;  // start, end, start, end, ...
  for (int x = 0; x < img.width; ++x) {
    bool coloured = false;
    for (int y = 0; y < img.height && !coloured; ++y) coloured = !greyish(img.pixel(x, y));
    if (coloured && (runs.empty() || runs.back() != x - 1)) runs.push_back(x), runs.push_back(x);
    if (coloured) runs.back() = x;
  }
  PixelBox b;
  if (runs.size() < 4) return b;
  b.x0 = runs[0], b.x1 = runs[3];
  for (int y = 0; y < img.height; ++y)
    for (int x = b.x0; x <= b.x1; ++x)
      if (!greyish(img.pixel(x, y))) b.y0 = std::min(b.y0, y), b.y1 = std::max(b.y1, y);
  return b;
}

TEST(ResultExport, RenderDrawsObjectsGreyAndFramesOnTheBodies) {
  test::TempDir tmp;
  SimulationResult r = scene(false, 1);
  render_result(r, tmp.file("with.png"), 1);
  const io::Image img = io::read_png(tmp.file("with.png"));
  const io::Rgb8 background = {232, 232, 232};
  // The strips span the panel; the ball sits at the middle between them.
  const PixelBox b = skin_box(img);
  ASSERT_GT(b.x1 - b.x0, 40);
  ASSERT_GT(b.y1 - b.y0, 40);
  const int cx = (b.x0 + b.x1) / 2, cy = (b.y0 + b.y1) / 2;
  const io::Rgb8 ball = img.pixel(cx, cy);
  EXPECT_TRUE(greyish(ball)) << int(ball[0]) << " " << int(ball[1]) << " " << int(ball[2]);
  EXPECT_GT(std::abs(int(ball[0]) - int(background[0])), 40) << int(ball[0]);
  // Between the ball and the right strip (x = 0.55, y = 0.2) the tilted floor
  // shows (its patch reaches ~0.4 m up the view), grey too; it lies behind
  // the strips, which stay coloured.
  const io::Rgb8 floor = img.pixel(cx + int(0.55 * (b.x1 - b.x0) / 2), b.y1 - (b.y1 - b.y0) / 10);
  EXPECT_TRUE(greyish(floor));
  EXPECT_NE(floor, background);
  EXPECT_NE(floor, ball);
  EXPECT_FALSE(greyish(img.pixel(b.x0 + 2, cy)));
  // The 2 km floor is clipped to the panel: left of it is background.
  for (int y = b.y0; y <= b.y1; ++y) ASSERT_EQ(img.pixel(b.x0 - 1, y), background) << y;
  // The same framing without the floor and without the ball.
  r.objects.clear();
  render_result(r, tmp.file("without.png"), 1);
  const io::Image bare = io::read_png(tmp.file("without.png"));
  const PixelBox c = skin_box(bare);
  EXPECT_EQ(b.x0, c.x0);
  EXPECT_EQ(b.x1, c.x1);
  EXPECT_EQ(b.y0, c.y0);
  EXPECT_EQ(b.y1, c.y1);
  EXPECT_EQ(bare.pixel(cx, cy), background);
}

}  // namespace
}  // namespace sflsh
