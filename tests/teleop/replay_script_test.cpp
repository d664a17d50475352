// scripts/replay_pose_stream.py (Python's struct: a second, independent
// implementation of the wire format) against the C++ server in a thread.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <thread>

#include "sflsh/teleop/pose_file.hpp"
#include "sflsh/teleop/pose_stream_server.hpp"
#include "test_support.hpp"

namespace sflsh::teleop {
namespace {

// The number after "key": in the script's one-line JSON summary.
double json_number(const std::string& out, const std::string& key) {
  const auto at = out.find("\"" + key + "\": ");
  if (at == std::string::npos) {
    ADD_FAILURE() << "no " << key << " in: " << out;
    return NAN;
  }
  return std::stod(out.substr(at + key.size() + 4));
}

TEST(ReplayScript, ReplaysAPoseFileWithAbuseAndMeasuresLatency) {
  test::TempDir dir;
  // 0.2 s of a slow 1 cm sweep in x, given at 50 Hz; the script resamples it at 1 kHz.
  std::vector<PoseSample> track;
  for (int i = 0; i <= 10; ++i) {
    PoseSample s;
    s.time = 0.02 * i;
    s.position = Vec3(0.001 * i, 0.3, 1.1);
    s.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(0.05 * i, Vec3::UnitY()));
    s.closure = 0.8 - 0.05 * i;
    track.push_back(s);
  }
  const std::string poses = dir.file("sweep.jsonl");
  write_pose_file(poses, track);

  PoseStreamServerOptions o;
  o.log = [](const std::string&) {};
  PoseStreamServer server(o);
  std::atomic<bool> stop{false};
  std::thread sim([&] {  // a 5 kHz loop answering each new sample with a spring force -1000 N/m * x
    while (!stop) {
      if (auto s = server.poll(0.0)) server.send_feedback(Vec3(-1000.0 * s->sample.position.x(), 0, 0), Vec3::Zero(), 0.0);
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
  });
  std::string out;
  const int rc = test::run_command("/usr/bin/python3 " + test::source_dir() + "/scripts/replay_pose_stream.py " + poses +
                                       " --port " + std::to_string(server.port()) +
                                       " --rate 1000 --drop 0.1 --corrupt 0.05 --seed 3 --wait 0.05 --json",
                                   &out);
  stop = true;
  sim.join();
  ASSERT_EQ(rc, 0) << out;

  EXPECT_EQ(json_number(out, "samples"), 201);  // 0.2 s at 1 kHz, both ends
  const double sent = json_number(out, "sent"), corrupted = json_number(out, "corrupted");
  EXPECT_GT(corrupted, 0);
  EXPECT_GT(json_number(out, "dropped"), 0);
  EXPECT_EQ(sent + json_number(out, "dropped"), 201);
  const PoseStreamCounters& c = server.counters();
  EXPECT_EQ(c.received, sent);
  EXPECT_EQ(c.rejected_total(), corrupted) << c.describe();
  EXPECT_EQ(c.accepted, sent - corrupted) << c.describe();
  // Each valid pose is answered, or superseded by a newer one before the
  // server polled (the feedback echoes the newest; on a loaded machine the
  // thread may wake late and drain several at once).
  EXPECT_GT(json_number(out, "answered"), 0) << out;
  EXPECT_EQ(json_number(out, "answered") + json_number(out, "unanswered"), sent - corrupted) << out;
  // The latency is a figure (scripts/teleop_figures.py), not a test: only that it was measured.
  const double latency = json_number(out, "latency_median_ms");
  EXPECT_TRUE(std::isfinite(latency) && latency >= 0) << out;
  // The last pose is the end of the sweep (x = 1 cm) unless it was dropped or corrupted.
  ASSERT_TRUE(server.last_good());
  const double x_last = server.last_good()->sample.position.x();
  EXPECT_NEAR(x_last, 0.01, 1e-4);
  const auto at = out.find("\"last_force\": [");
  ASSERT_NE(at, std::string::npos) << out;
  EXPECT_DOUBLE_EQ(std::stod(out.substr(at + 15)), -1000.0 * x_last);
}

TEST(ReplayScript, MissingPoseFileGivesOneLineAndNonZeroExit) {
  test::TempDir dir;
  std::string out;
  const int rc = test::run_command("/usr/bin/python3 " + test::source_dir() + "/scripts/replay_pose_stream.py " +
                                       dir.file("none.csv") + " --port 9",
                                   &out);
  EXPECT_NE(rc, 0);
  EXPECT_NE(out.find("none.csv: cannot read"), std::string::npos) << out;
}

}  // namespace
}  // namespace sflsh::teleop
