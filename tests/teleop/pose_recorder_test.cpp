#include "sflsh/teleop/pose_recorder.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <filesystem>

#include "sflsh/teleop/pose_track.hpp"
#include "test_support.hpp"

namespace sflsh::teleop {
namespace {

StreamSample stream_sample(std::uint64_t seq, double receive_time, double x) {
  StreamSample s;
  s.sequence = seq;
  s.receive_time = receive_time;
  s.sample.time = 100.0 + receive_time;  // device clock: not what is recorded
  s.sample.position = Vec3(x, 1.0 / 3.0, -2.0);
  s.sample.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(x, Vec3(0.6, 0.0, 0.8)));
  s.sample.closure = 0.5 + x;
  return s;
}

TEST(PoseRecorder, WritesReceiveTimesAndPosesThatReadBackExactly) {
  test::TempDir dir;
  for (const char* name : {"session.csv", "session.jsonl"}) {
    PoseRecorder rec(dir.file(name));
    for (int i = 0; i < 4; ++i) rec.record(stream_sample(i + 1, 0.002 * i + 0.001, 0.1 * i));
    EXPECT_FALSE(std::filesystem::exists(dir.file(name))) << "visible before finish()";
    rec.finish();
    EXPECT_EQ(rec.rows(), 4);
    const auto back = read_pose_file(dir.file(name));
    ASSERT_EQ(back.size(), 4u);
    for (int i = 0; i < 4; ++i) {
      const StreamSample s = stream_sample(i + 1, 0.002 * i + 0.001, 0.1 * i);
      EXPECT_EQ(back[i].time, s.receive_time);
      EXPECT_EQ(back[i].position, s.sample.position);
      EXPECT_EQ(back[i].orientation.coeffs(), s.sample.orientation.coeffs());
      EXPECT_EQ(back[i].closure, s.sample.closure);
    }
  }
}

TEST(PoseRecorder, RejectsNonIncreasingReceiveTimesAndLeavesNothingWithoutFinish) {
  test::TempDir dir;
  {
    PoseRecorder rec(dir.file("r.csv"));
    rec.record(stream_sample(1, 0.5, 0.0));
    test::expect_error([&] { rec.record(stream_sample(2, 0.5, 0.0)); }, {"r.csv", "receive time 0.5", "not after"});
  }
  EXPECT_FALSE(std::filesystem::exists(dir.file("r.csv")));
  EXPECT_FALSE(std::filesystem::exists(dir.file("r.csv.partial")));
  test::expect_error([&] { PoseRecorder r(dir.file("r.txt")); }, {"r.txt", "extension"});
}

// A live session over the loopback socket, recorded, then replayed offline:
// the offline poses equal the live ones bit for bit at every step.
TEST(PoseRecorder, OfflineReplayOfARecordedSessionGivesTheLivePoses) {
  test::TempDir dir;
  PoseStreamServerOptions o;
  o.log = [](const std::string&) {};
  PoseStreamServer server(o);
  const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  to.sin_port = htons(static_cast<std::uint16_t>(server.port()));

  PoseRecorder rec(dir.file("live.csv"));
  const double dt = 1.0 / 500.0;  // physics step
  std::vector<PoseSample> live;   // the pose the simulation used at each step
  std::vector<double> step_times;
  std::uint64_t seq = 0;
  for (int step = 0; step < 60; ++step) {
    const double t = step * dt;
    // 0 to 3 device samples between two steps (a 1 kHz device, jittered), one of them garbage.
    const int burst = step % 4;
    for (int k = 0; k < burst; ++k) {
      ++seq;
      PoseMessage m;
      m.sequence = seq;
      m.sample.time = 1e-3 * seq;
      m.sample.position = Vec3(std::sin(0.01 * seq), 0.2, 0.001 * seq);
      m.sample.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(0.01 * seq, Vec3::UnitX()));
      m.sample.closure = 0.5 + 0.4 * std::cos(0.02 * seq);
      auto bytes = encode_pose(m);
      if (seq % 7 == 0)  // all-ones bytes: the closure becomes NaN, rejected
        for (int b = 80; b < 88; ++b) bytes[b] = 0xff;
      ::sendto(fd, bytes.data(), bytes.size(), 0, reinterpret_cast<const sockaddr*>(&to), sizeof to);
    }
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    std::optional<StreamSample> newest;
    while (server.counters().received < static_cast<long>(seq) && std::chrono::steady_clock::now() < deadline)
      if (auto s = server.poll(t)) newest = s;
    if (newest) rec.record(*newest);
    if (server.last_good()) {
      live.push_back(server.last_good()->sample);
      step_times.push_back(t);
    }
  }
  ::close(fd);
  rec.finish();
  ASSERT_GT(server.counters().rejected_total(), 0);
  ASSERT_GT(live.size(), 40u);

  const PoseTrack replay(read_pose_file(dir.file("live.csv")), "live.csv");
  for (std::size_t i = 0; i < live.size(); ++i) {
    const PoseSample r = replay.at(step_times[i], PoseInterpolation::kHold);
    EXPECT_EQ(r.position, live[i].position) << "step time " << step_times[i];
    EXPECT_EQ(r.orientation.coeffs(), live[i].orientation.coeffs());
    EXPECT_EQ(r.closure, live[i].closure);
  }
}

}  // namespace
}  // namespace sflsh::teleop
