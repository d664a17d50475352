// A run driven into NaN on purpose (the hidden, test-only
// `--inject-nan-at-step`) stops there with one error line naming the step,
// the term and the body, and leaves a valid, readable result holding the
// frames before the step, marked incomplete, with no NaN in it. Motions with
// a NaN frame are rejected at load, naming the frame.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <filesystem>
#include <limits>

#include "sflsh/asset/avatar_file.hpp"
#include "sflsh/io/npz.hpp"
#include "sflsh/motion/load_motion.hpp"
#include "sflsh/scene/result_export.hpp"
#include "sflsh/scene/result_file.hpp"
#include "sim/synthetic_avatar.hpp"
#include "test_support.hpp"

using namespace sflsh;
namespace fs = std::filesystem;

namespace {

int run(const std::string& args, std::string* out) {
  return test::run_command(test::sflsh_binary() + " -q " + args, out);
}

}  // namespace

TEST(NumericalGuardCli, ARunMeetingNaNStopsAndLeavesAnIncompleteReadableResult) {
  test::TempDir dir;
  write_avatar(test::make_synthetic_avatar(), dir.file("a.h5"));
  const std::string out = dir.file("r.h5");
  // dt 1/60, 30 frames/s: frames at steps 0, 2, 4 are made before step 5.
  std::string text;
  const int code = run("simulate --avatar " + dir.file("a.h5") + " --motion builtin:shake --seconds 0.5 --out " + out +
                           " --bones kinematic --inject-nan-at-step 5",
                       &text);
  EXPECT_EQ(code, 1) << text;
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 1) << text;
  for (const std::string frag : std::vector<std::string>{"step 5", "t = 0.0833", "body 'avatar'", "marked incomplete", out})
    EXPECT_NE(text.find(frag), std::string::npos) << "'" << frag << "' not in: " << text;
  ASSERT_TRUE(fs::exists(out)) << text;
  EXPECT_FALSE(fs::exists(out + ".partial"));

  const SimulationResult r = read_simulation_result(out);
  EXPECT_TRUE(r.incomplete);
  EXPECT_NE(r.stop_reason.find("step 5"), std::string::npos) << r.stop_reason;
  ASSERT_EQ(r.frame_time.size(), 3u);
  EXPECT_NEAR(r.frame_time.back(), 4.0 / 60, 1e-12);
  EXPECT_EQ(r.step_time.size(), 4u) << "the steps before the stop, not the failing one";
  for (size_t i = 0; i < r.frame_time.size(); ++i) {
    EXPECT_TRUE(r.frame_positions[i].allFinite() && r.frame_displacement[i].allFinite() &&
                r.frame_joints[i].allFinite() && r.frame_reduced[i].allFinite())
        << "frame " << i;
  }
  for (double e : r.step_energy) EXPECT_TRUE(std::isfinite(e));
  EXPECT_NE(r.describe().find("INCOMPLETE"), std::string::npos);
  EXPECT_NE(export_result(r, dir.file("x.pc2")).find("INCOMPLETE"), std::string::npos);

  // `sflsh inspect` says so too; a complete run says "complete".
  ASSERT_EQ(run("inspect " + out, &text), 0) << text;
  EXPECT_NE(text.find("INCOMPLETE"), std::string::npos) << text;
  EXPECT_NE(text.find("3 frames"), std::string::npos) << text;
  ASSERT_EQ(run("simulate --avatar " + dir.file("a.h5") + " --motion builtin:shake --seconds 0.1 --out " +
                    dir.file("ok.h5"),
                &text),
            0)
      << text;
  EXPECT_FALSE(read_simulation_result(dir.file("ok.h5")).incomplete);
  ASSERT_EQ(run("inspect " + dir.file("ok.h5"), &text), 0) << text;
  EXPECT_NE(text.find("complete"), std::string::npos) << text;
  EXPECT_EQ(text.find("INCOMPLETE"), std::string::npos) << text;
}

TEST(NumericalGuardCli, MotionsWithANaNFrameAreRejectedNamingTheFrame) {
  test::TempDir dir;
  // An AMASS-style file of 4 frames at 20 fps; frame 2 of 'poses' holds a NaN.
  std::map<std::string, io::NpyArray> m;
  m["poses"] = {{4, 72}, "<f8", std::vector<double>(4 * 72, 0.0)};
  m["trans"] = {{4, 3}, "<f8", std::vector<double>(4 * 3, 0.0)};
  m["mocap_framerate"] = {{}, "<f8", {20.0}};
  m["poses"].data[2 * 72 + 7] = std::numeric_limits<double>::quiet_NaN();
  io::write_npz(dir.file("nan.npz"), m);
  std::string text;
  EXPECT_EQ(run("motion info " + dir.file("nan.npz"), &text), 1) << text;
  for (const std::string frag : {"nan.npz", "'poses'", "frame 2", "t = 0.1 s", "column 7"})
    EXPECT_NE(text.find(frag), std::string::npos) << "'" << frag << "' not in: " << text;

  // trans: the same, in another key.
  m["poses"].data[2 * 72 + 7] = 0;
  m["trans"].data[3 * 3 + 1] = std::numeric_limits<double>::infinity();
  io::write_npz(dir.file("inf.npz"), m);
  test::expect_error([&] { load_motion(dir.file("inf.npz")); }, {"inf.npz", "'trans'", "frame 3"});

  // BVH: a NaN channel in the second motion line.
  std::ofstream(dir.file("nan.bvh")) << "HIERARCHY\nROOT Hips\n{\n OFFSET 0 0 0\n CHANNELS 6 Xposition Yposition "
                                         "Zposition Zrotation Xrotation Yrotation\n End Site\n {\n  OFFSET 0 10 0\n }\n}\n"
                                         "MOTION\nFrames: 2\nFrame Time: 0.1\n0 90 0 0 0 0\n0 nan 0 0 0 0\n";
  test::expect_error([&] { load_motion(dir.file("nan.bvh")); }, {"nan.bvh", "frame 2"});
}
