// `sflsh simulate --use-file-betas`: the AMASS file's betas build (then reuse)
// an avatar of that shape from the given avatar's body model; bad input fails
// with one clear line and no result file.
#include <gtest/gtest.h>

#include <filesystem>

#include "sflsh/asset/avatar_file.hpp"
#include "sflsh/io/hdf5_file.hpp"
#include "sflsh/io/npz.hpp"
#include "sflsh/precompute/file_betas_avatar.hpp"
#include "sflsh/scene/result_file.hpp"
#include "sflsh/scene/simulation_run.hpp"
#include "sim/synthetic_avatar.hpp"
#include "test_support.hpp"

using namespace sflsh;

namespace {

// Coarse built-in body as in pipeline_cli_test.cpp: ~10k tets, 8 handles.
const char* kCoarse = " --handles 8 --cell-size 0.08 --facet-size 0.06 --facet-distance 0.004";

/// A 12-frame AMASS-style .npz (60 fps, a small knee bend); `betas` are
/// stored unless empty.
void write_motion(const std::string& path, const std::vector<double>& betas) {
  const int T = 12;
  std::map<std::string, io::NpyArray> a;
  a["poses"].shape = {T, 72};
  a["poses"].data.assign(T * 72, 0.0);
  for (int t = 0; t < T; ++t) a["poses"].data[t * 72 + 3 * 4] = 0.03 * t;  // left knee
  a["trans"].shape = {T, 3};
  a["trans"].data.assign(T * 3, 0.0);
  a["mocap_framerate"].shape = {};
  a["mocap_framerate"].data = {60.0};
  if (!betas.empty()) {
    a["betas"].shape = {std::int64_t(betas.size())};
    a["betas"].data = betas;
  }
  io::write_npz(path, a);
}

int run(const std::string& args, std::string* out) {
  return test::run_command(test::sflsh_binary() + " -q " + args, out);
}

}  // namespace

TEST(FileBetas, FitBetasTruncatesOrPads) {
  std::string note;
  VecX b = fit_betas(VecX::LinSpaced(16, 1, 16), 10, &note);
  ASSERT_EQ(b.size(), 10);
  EXPECT_EQ(b[9], 10.0);
  EXPECT_NE(note.find("truncated from 16 to the model's 10"), std::string::npos) << note;
  b = fit_betas(VecX::Constant(3, 2.0), 10, &note);
  ASSERT_EQ(b.size(), 10);
  EXPECT_EQ(b[2], 2.0);
  EXPECT_EQ(b.tail(7).norm(), 0.0);
  EXPECT_NE(note.find("zero-padded from 3"), std::string::npos) << note;
  b = fit_betas(VecX::Constant(10, 1.0), 10, &note);
  EXPECT_EQ(b, VecX::Constant(10, 1.0));
  EXPECT_TRUE(note.empty()) << note;
}

TEST(FileBetas, BadInputFailsWithOneClearLineAndNoOutput) {
  test::TempDir dir;
  // A small valid avatar file (the synthetic box with SMPL's skeleton), built
  // from the procedural body according to its meta data.
  Avatar a = test::make_synthetic_avatar();
  a.model_source = "procedural";
  a.model_hash = "0123456789abcdef";  // not the procedural body's hash
  write_avatar(a, dir.file("changed.h5"));
  a.model_source = dir.file("no_such_model.h5");
  write_avatar(a, dir.file("missing.h5"));
  // A relative model path is also looked up next to the avatar (found there: then the hash differs).
  std::filesystem::copy_file(test::generated_fixture("tiny_smpl.npz"), dir.file("tiny_smpl.npz"));
  a.model_source = "tiny_smpl.npz";
  write_avatar(a, dir.file("relative.h5"));
  write_motion(dir.file("betas.npz"), {0.5, -0.5});
  write_motion(dir.file("nobetas.npz"), {});
  const std::string out_file = dir.file("r.h5");
  struct Case {
    std::string args;
    std::vector<std::string> expect;
  } cases[] = {
      {"--avatar " + dir.file("changed.h5") + " --motion builtin:jump", {"--use-file-betas needs an AMASS .npz", "builtin:jump"}},
      {"--avatar " + dir.file("changed.h5") + " --motion " + dir.file("walk.bvh"),
       {"--use-file-betas needs an AMASS .npz", "walk.bvh"}},
      {"--avatar " + dir.file("changed.h5") + " --motion " + dir.file("nobetas.npz"),
       {"nobetas.npz", "no 'betas'"}},
      {"--avatar " + dir.file("changed.h5") + " --motion " + dir.file("betas.npz"),
       {"changed.h5", "hash 0123456789abcdef", "now has hash"}},
      {"--avatar " + dir.file("missing.h5") + " --motion " + dir.file("betas.npz"),
       {"missing.h5", "no_such_model.h5", "cannot be found"}},
      {"--avatar " + dir.file("relative.h5") + " --motion " + dir.file("betas.npz"),
       {"relative.h5", "'tiny_smpl.npz' with hash 0123456789abcdef, but '" + dir.file("tiny_smpl.npz") + "' now has hash"}},
  };
  for (const auto& c : cases) {
    std::string out;
    const int code = run("simulate --use-file-betas --cache-dir " + dir.file("cache") + " " + c.args + " --out " + out_file,
                         &out);
    EXPECT_NE(code, 0) << c.args;
    for (const auto& e : c.expect) EXPECT_NE(out.find(e), std::string::npos) << c.args << "\n" << out;
    EXPECT_NE(out.find("error"), std::string::npos) << out;
    EXPECT_FALSE(std::filesystem::exists(out_file)) << c.args;
  }
  EXPECT_FALSE(std::filesystem::exists(dir.file("cache"))) << "nothing was built";
}

// One test: the coarse precompute runs once (ctest runs each TEST in its own process).
TEST(FileBetas, BuildsTheFileShapeOnceThenReusesIt) {
  test::TempDir dir;
  const std::string cache = dir.file("cache"), base = dir.file("base.h5");
  std::string out;
  ASSERT_EQ(run(std::string("precompute") + kCoarse + " --cache-dir " + cache + " --out " + base, &out), 0) << out;
  std::vector<double> betas16(16, 0.0);
  betas16[0] = 1.5;   // size
  betas16[1] = -1.0;  // girth
  betas16[12] = 3.0;  // beyond the model's 10: dropped
  write_motion(dir.file("m16.npz"), betas16);
  write_motion(dir.file("m3.npz"), {-1.0, 0.5, 0.25});
  auto simulate = [&](const std::string& motion, const std::string& result) {
    std::string o;
    const int code = run("simulate --avatar " + base + " --motion " + dir.file(motion) +
                             " --use-file-betas --seconds 0.1 --cache-dir " + cache + " --out " + dir.file(result),
                         &o);
    EXPECT_EQ(code, 0) << o;
    return o;
  };

  out = simulate("m16.npz", "r1.h5");
  EXPECT_NE(out.find("truncated from 16 to the model's 10"), std::string::npos) << out;
  EXPECT_NE(out.find("built and cached as"), std::string::npos) << out;
  EXPECT_NE(out.find("template stage from cache"), std::string::npos) << out;
  EXPECT_NE(out.find("8 handles"), std::string::npos) << out;
  EXPECT_EQ(out.find("note:"), std::string::npos) << "the base avatar's mesh is in the cache\n" << out;
  const SimulationResult r1 = read_simulation_result(dir.file("r1.h5"));
  ASSERT_TRUE(std::filesystem::exists(r1.avatar)) << r1.avatar;
  EXPECT_EQ(std::filesystem::path(r1.avatar).parent_path(), std::filesystem::path(cache));
  const Avatar b = read_avatar(base), s = read_avatar(r1.avatar);
  ASSERT_EQ(s.betas.size(), 10);
  EXPECT_EQ(s.betas[0], 1.5);
  EXPECT_EQ(s.betas[1], -1.0);
  EXPECT_EQ(s.betas.tail(8).norm(), 0.0);
  EXPECT_EQ(s.num_handles(), b.num_handles());
  EXPECT_EQ(s.model_hash, b.model_hash);
  EXPECT_EQ(s.tet.elements, b.tet.elements) << "same template mesh as the given avatar";
  EXPECT_GT((s.joints_rest - b.joints_rest).norm(), 1e-3) << "a different shape moves the skeleton";
  EXPECT_EQ(r1.step_time.size(), 6u);

  out = simulate("m16.npz", "r2.h5");
  EXPECT_NE(out.find("reused from cache"), std::string::npos) << out;
  EXPECT_EQ(read_simulation_result(dir.file("r2.h5")).avatar, r1.avatar);

  out = simulate("m3.npz", "r3.h5");
  EXPECT_NE(out.find("zero-padded from 3 to the model's 10"), std::string::npos) << out;
  const Avatar s3 = read_avatar(read_simulation_result(dir.file("r3.h5")).avatar);
  ASSERT_EQ(s3.betas.size(), 10);
  EXPECT_EQ(s3.betas[2], 0.25);
  EXPECT_EQ(s3.betas.tail(7).norm(), 0.0);
}
