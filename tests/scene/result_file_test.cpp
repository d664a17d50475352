#include <gtest/gtest.h>

#include <filesystem>

#include "sflsh/core/error.hpp"
#include "sflsh/io/hdf5_file.hpp"
#include "sflsh/scene/result_file.hpp"
#include "sflsh/scene/simulation_run.hpp"
#include "test_support.hpp"

using namespace sflsh;

namespace {
SimulationResult small_result() {
  SimulationResult r;
  r.avatar = "a.h5";
  r.motion = "builtin:jump";
  r.dt = 1.0 / 60;
  r.bones_dynamic = true;
  r.faces.resize(1, 3);
  r.faces << 0, 1, 2;
  r.surface_rest = Points::Random(3, 3);
  for (int f = 0; f < 4; ++f) {
    r.frame_time.push_back(f / 30.0);
    r.frame_step_ms.push_back(1.0 + f);
    r.frame_positions.push_back(Points::Constant(3, 3, 0.25 * f));
    r.frame_displacement.push_back(Points::Constant(3, 3, 0.001 * f));
    r.frame_joints.push_back(Points::Constant(24, 3, -0.5 * f));
    r.frame_reduced.push_back(VecX::Constant(6, 0.01 * f));
  }
  r.num_frames = 4;
  for (int s = 0; s < 8; ++s) {
    r.step_time.push_back((s + 1) / 60.0);
    r.step_energy.push_back(s);
    r.step_grad_norm.push_back(0.5 * s);
    r.step_decrement.push_back(0.1 * s);
    r.step_outcome.push_back(s == 3 ? 1 : 0);
    r.step_ms.push_back(1.5);
  }
  return r;
}
}  // namespace

TEST(ResultFile, RoundTripKeepsFramesAndDiagnostics) {
  test::TempDir tmp;
  const SimulationResult r = small_result();
  write_simulation_result(r, tmp.file("r.h5"));
  const SimulationResult b = read_simulation_result(tmp.file("r.h5"));
  ASSERT_EQ(b.num_frames, 4);
  EXPECT_EQ(b.frame_time, r.frame_time);
  EXPECT_EQ(b.frame_joints[3], r.frame_joints[3]);
  EXPECT_EQ(b.frame_reduced[2], r.frame_reduced[2]);
  // Positions are stored as float32.
  EXPECT_LT((b.frame_positions[2] - r.frame_positions[2]).cwiseAbs().maxCoeff(), 1e-6);
  EXPECT_EQ(b.step_energy, r.step_energy);
  EXPECT_EQ(b.damped, 1);
  EXPECT_EQ(b.accepted, 7);
  EXPECT_TRUE(b.bones_dynamic);
  io::Hdf5File f(tmp.file("r.h5"), io::Hdf5File::Mode::Read);
  EXPECT_EQ(f.shape("/frames/positions"), (std::vector<std::int64_t>{4, 3, 3}));
  EXPECT_EQ(f.shape("/frames/joints"), (std::vector<std::int64_t>{4, 24, 3}));
}

TEST(ResultFile, UnfinishedStreamLeavesNoFile) {
  test::TempDir tmp;
  const SimulationResult r = small_result();
  {
    ResultWriter w(tmp.file("r.h5"), r.faces, r.surface_rest, 6);
    w.add_frame({0.0, 1.0, r.frame_positions[0], r.frame_displacement[0], r.frame_joints[0], r.frame_reduced[0]});
    // no finish(): e.g. the simulation threw
  }
  EXPECT_FALSE(std::filesystem::exists(tmp.file("r.h5")));
}

TEST(ResultFile, RejectsOtherFiles) {
  test::TempDir tmp;
  {
    io::Hdf5File f(tmp.file("x.h5"), io::Hdf5File::Mode::Write);
    f.write_scalar("/something", 1.0);
    f.commit();
  }
  EXPECT_THROW(read_simulation_result(tmp.file("x.h5")), Error);
}
