// End-to-end tests of `sflsh body info|export|render` through the built binary.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "sflsh/body/body_model.hpp"
#include "sflsh/io/mesh_export.hpp"
#include "sflsh/io/npz.hpp"
#include "sflsh/io/png_image.hpp"
#include "test_support.hpp"

namespace sflsh {
namespace {

namespace fs = std::filesystem;

int sflsh(const std::string& args, std::string* out) {
  return test::run_command(test::sflsh_binary() + " " + args, out);
}

std::string read_text(const std::string& path) {
  std::stringstream ss;
  ss << std::ifstream(path, std::ios::binary).rdbuf();
  return ss.str();
}

Vec3 extent(const Points& V) { return V.colwise().maxCoeff() - V.colwise().minCoeff(); }

TEST(BodyCli, InfoReportsCountsAndChecks) {
  std::string out;
  ASSERT_EQ(sflsh("body info", &out), 0) << out;
  EXPECT_NE(out.find("joints:       24"), std::string::npos) << out;
  EXPECT_NE(out.find("closed:       yes"), std::string::npos) << out;
  EXPECT_NE(out.find("manifold:     yes"), std::string::npos) << out;
  EXPECT_NE(out.find("shape space:  "), std::string::npos) << out;
  EXPECT_NE(out.find("beta[0]: "), std::string::npos) << out;
  EXPECT_NE(out.find("height:       1."), std::string::npos) << out;

  ASSERT_EQ(sflsh("body info --json --betas 1", &out), 0) << out;
  EXPECT_NE(out.find("\"joints\": 24,"), std::string::npos) << out;
  EXPECT_NE(out.find("\"closed\": true,"), std::string::npos) << out;
  EXPECT_NE(out.find("\"betas\": [1],"), std::string::npos) << out;
}

TEST(BodyCli, ExportWritesPosedSurfaceAndJoints) {
  test::TempDir dir;
  std::string out;
  ASSERT_EQ(sflsh("body export --out " + dir.file("t.obj") + " --joints " + dir.file("j.csv"), &out), 0) << out;
  ASSERT_EQ(sflsh("body export --pose-preset apose --out " + dir.file("a.ply"), &out), 0) << out;
  ASSERT_EQ(sflsh("body export --betas 2 --out " + dir.file("tall.glb"), &out), 0) << out;
  ASSERT_EQ(sflsh("body export --betas -2 --out " + dir.file("short.glb"), &out), 0) << out;

  const io::ImportedMesh t = io::read_mesh(dir.file("t.obj")), a = io::read_mesh(dir.file("a.ply"));
  EXPECT_GT(t.vertices.rows(), 3000);
  EXPECT_EQ(t.vertices.rows(), a.vertices.rows());
  EXPECT_EQ(t.faces.rows(), a.faces.rows());
  // Arms down (A-pose) make the body narrower than arms out (T-pose).
  EXPECT_LT(extent(a.vertices).x(), 0.85 * extent(t.vertices).x());
  // β0 is overall size: +2 is taller than -2.
  EXPECT_GT(extent(io::read_mesh(dir.file("tall.glb")).vertices).y(),
            extent(io::read_mesh(dir.file("short.glb")).vertices).y() + 0.1);

  const std::string csv = read_text(dir.file("j.csv"));
  EXPECT_EQ(csv.rfind("index,name,parent,x,y,z\n0,pelvis,-1,", 0), 0u) << csv;
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 25);
}

TEST(BodyCli, PoseFilesMatchPresetsAndTranslation) {
  test::TempDir dir;
  const BodyPose apose = pose_preset("apose");
  io::NpyArray pose;
  pose.shape = {24, 3};
  pose.dtype = "<f8";
  pose.data.assign(apose.axis_angle.data(), apose.axis_angle.data() + 72);
  io::write_npz(dir.file("apose.npz"), {{"pose", pose}});
  {
    std::ofstream txt(dir.file("apose.txt"));
    txt << "# SMPL axis-angle, 24 joints\n";
    txt.precision(17);
    for (int i = 0; i < 72; ++i) txt << pose.data[size_t(i)] << (i % 3 == 2 ? "\n" : " ");
  }
  std::string out;
  ASSERT_EQ(sflsh("body export --pose-preset apose --out " + dir.file("preset.obj"), &out), 0) << out;
  ASSERT_EQ(sflsh("body export --pose " + dir.file("apose.npz") + " --out " + dir.file("npz.obj"), &out), 0) << out;
  ASSERT_EQ(sflsh("body export --pose " + dir.file("apose.txt") + " --out " + dir.file("txt.obj"), &out), 0) << out;
  EXPECT_EQ(read_text(dir.file("npz.obj")), read_text(dir.file("preset.obj")));
  EXPECT_EQ(read_text(dir.file("txt.obj")), read_text(dir.file("preset.obj")));

  ASSERT_EQ(sflsh("body export --pose-preset apose --translation 1,2,3 --out " + dir.file("moved.obj"), &out), 0)
      << out;
  const Points p = io::read_mesh(dir.file("preset.obj")).vertices, m = io::read_mesh(dir.file("moved.obj")).vertices;
  const Vec3 shift = (m.colwise().minCoeff() - p.colwise().minCoeff()).transpose();
  EXPECT_LT((shift - Vec3(1, 2, 3)).norm(), 1e-5);
}

TEST(BodyCli, RenderWritesAPicture) {
  test::TempDir dir;
  std::string out;
  ASSERT_EQ(sflsh("body render --pose-preset walk --size 200 --out " + dir.file("b.png"), &out), 0) << out;
  const io::Image img = io::read_png(dir.file("b.png"));
  EXPECT_EQ(img.height, 200);
  EXPECT_EQ(img.width, 250);
  const io::Rgb8 bg = img.pixel(0, 0);
  EXPECT_EQ(img.pixel(img.width - 1, img.height - 1), bg);
  int body = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) body += img.pixel(x, y) != bg;
  EXPECT_GT(body, img.width * img.height / 20) << "the body covers a visible part of the picture";
}

/// Runs a failing command: non-zero exit, one line naming `expect`, no output files.
void expect_clean_failure(const std::string& args, const std::string& expect, const test::TempDir& dir) {
  std::string out;
  EXPECT_NE(sflsh(args, &out), 0) << args;
  EXPECT_NE(out.find(expect), std::string::npos) << args << "\n" << out;
  EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 1) << out;
  EXPECT_TRUE(fs::is_empty(dir.path())) << args;
}

TEST(BodyCli, BadFilesFailCleanly) {
  test::TempDir dir;
  const std::string obj = " --out " + dir.file("x.obj");
  expect_clean_failure("body export --out " + dir.file("x.stl"), ".obj, .ply, .glb, .gltf", dir);
  expect_clean_failure("body export --model " + dir.file("missing.h5") + obj, "missing.h5", dir);
  expect_clean_failure("body export --model " + dir.file("model.xyz") + obj, "model.xyz", dir);
  expect_clean_failure("body export --pose " + dir.file("none.npz") + obj, "none.npz", dir);
  test::TempDir inputs;  // kept apart so that `dir` must stay empty
  io::NpyArray poses;
  poses.shape = {72};
  poses.data.assign(72, 0.0);
  io::write_npz(inputs.file("wrong_key.npz"), {{"poses", poses}});
  expect_clean_failure("body export --pose " + inputs.file("wrong_key.npz") + obj, "key 'pose' is missing", dir);
  std::ofstream(inputs.file("short.txt")) << "0 0 0\n";
  expect_clean_failure("body export --pose " + inputs.file("short.txt") + obj, "expected 72", dir);
}

TEST(BodyCli, BadParametersFailCleanly) {
  test::TempDir dir;
  const std::string obj = " --out " + dir.file("x.obj");
  expect_clean_failure("body export --betas 1,abc" + obj, "abc", dir);
  {
    // More β than any SMPL-format model has shape directions (SMPL: 10 or 300).
    std::string betas = "0";
    for (int i = 0; i < 300; ++i) betas += ",0";
    expect_clean_failure("body export --betas " + betas + obj, "shape directions", dir);
  }
  expect_clean_failure("body export --pose-preset jump" + obj, "jump", dir);
  expect_clean_failure("body export --translation 1,2" + obj, "--translation", dir);
  expect_clean_failure("body render --out " + dir.file("x.jpg"), ".png", dir);
  expect_clean_failure("body export --joints " + dir.file("j.txt") + obj, ".csv, .json", dir);
}

}  // namespace
}  // namespace sflsh
