#include "sflsh/teleop/pose_stream_server.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <limits>
#include <thread>

#include "test_support.hpp"

namespace sflsh::teleop {
namespace {

// A device's end: a UDP socket that sends to the server's port and reads feedback.
class Client {
 public:
  explicit Client(int port) {
    fd_ = ::socket(AF_INET, SOCK_DGRAM, 0);
    to_.sin_family = AF_INET;
    to_.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    to_.sin_port = htons(static_cast<std::uint16_t>(port));
    timeval tv{1, 0};  // a lost feedback fails the test after 1 s instead of hanging
    ::setsockopt(fd_, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  }
  ~Client() { ::close(fd_); }
  void send(const std::uint8_t* data, std::size_t n) {
    ASSERT_EQ(::sendto(fd_, data, n, 0, reinterpret_cast<const sockaddr*>(&to_), sizeof to_), static_cast<ssize_t>(n));
  }
  void send_pose(const PoseMessage& m) {
    const auto b = encode_pose(m);
    send(b.data(), b.size());
  }
  std::optional<FeedbackMessage> receive() {
    std::uint8_t buf[256];
    const ssize_t n = ::recv(fd_, buf, sizeof buf, 0);
    if (n < 0) return std::nullopt;
    return decode_feedback(buf, static_cast<std::size_t>(n)).message;
  }

 private:
  int fd_ = -1;
  sockaddr_in to_{};
};

PoseMessage pose(std::uint64_t seq, double t, double x) {
  PoseMessage m;
  m.sequence = seq;
  m.sample.time = t;
  m.sample.position = Vec3(x, 0.5, 1.0);
  m.sample.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(0.2 * x, Vec3::UnitZ()));
  m.sample.closure = 0.3;
  return m;
}

// Polls until `n` datagrams have arrived in total (loopback delivery is
// immediate in practice; the deadline only guards against a hang).
std::optional<StreamSample> poll_until(PoseStreamServer& s, long n, double now,
                                       std::vector<StreamSample>* accepted = nullptr) {
  std::optional<StreamSample> newest;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (s.counters().received < n && std::chrono::steady_clock::now() < deadline) {
    if (auto r = s.poll(now, accepted)) newest = r;
  }
  return newest;
}

struct Fixture {
  std::vector<std::string> log;
  PoseStreamServer server{[this] {
    PoseStreamServerOptions o;
    o.log = [this](const std::string& line) { log.push_back(line); };
    return o;
  }()};
  Client client{server.port()};
};

TEST(PoseStreamServer, PicksAFreePortAndReportsIt) {
  PoseStreamServer a, b;
  EXPECT_GT(a.port(), 0);
  EXPECT_GT(b.port(), 0);
  EXPECT_NE(a.port(), b.port());
  // The port is taken: a second server on it fails with one clear error.
  PoseStreamServerOptions o;
  o.port = a.port();
  test::expect_error([&] { PoseStreamServer c(o); }, {"cannot bind UDP 127.0.0.1:" + std::to_string(a.port())});
}

TEST(PoseStreamServer, NothingPendingGivesNothingAndNoFeedbackTarget) {
  Fixture f;
  EXPECT_FALSE(f.server.poll(0.0));
  EXPECT_FALSE(f.server.last_good());
  EXPECT_FALSE(f.server.send_feedback(Vec3::Zero(), Vec3::Zero(), 0.0));
  EXPECT_EQ(f.server.counters().received, 0);
}

TEST(PoseStreamServer, DrainsAllPendingReturnsNewestAndAnswersTheSender) {
  Fixture f;
  for (int i = 1; i <= 3; ++i) f.client.send_pose(pose(i, 0.001 * i, 0.001 * i));
  std::vector<StreamSample> accepted;
  const auto newest = poll_until(f.server, 3, 0.5, &accepted);
  ASSERT_TRUE(newest);
  EXPECT_EQ(newest->sequence, 3u);
  EXPECT_EQ(newest->sample.time, 0.003);
  EXPECT_EQ(newest->sample.position.x(), 0.003);
  EXPECT_EQ(newest->receive_time, 0.5);
  ASSERT_EQ(accepted.size(), 3u);
  EXPECT_EQ(accepted[0].sequence, 1u);
  EXPECT_EQ(f.server.counters().accepted, 3);

  ASSERT_TRUE(f.server.send_feedback(Vec3(1.5, -2.0, 0.25), Vec3(0.125, 0.0, -0.5), 0.5));
  const auto fb = f.client.receive();
  ASSERT_TRUE(fb);
  EXPECT_EQ(fb->sequence, 3u);
  EXPECT_EQ(fb->sim_time, 0.5);
  EXPECT_EQ(fb->force, Vec3(1.5, -2.0, 0.25));
  EXPECT_EQ(fb->torque, Vec3(0.125, 0.0, -0.5));
  EXPECT_EQ(f.server.feedback_sent(), 1);
}

TEST(PoseStreamServer, EveryKindOfBadDatagramIsLoggedCountedAndTheLastGoodPoseHeld) {
  Fixture f;
  f.client.send_pose(pose(5, 1.0, 0.1));
  ASSERT_TRUE(poll_until(f.server, 1, 0.0));

  const auto good_bytes = encode_pose(pose(6, 1.001, 0.1));
  const std::uint8_t garbage[] = {'h', 'e', 'l', 'l', 'o', ' ', 'w', 'o', 'r', 'l', 'd'};
  f.client.send(garbage, sizeof garbage);                // bad magic
  f.client.send(good_bytes.data(), 40);                  // truncated
  auto v2 = good_bytes;
  v2[4] = 7;
  f.client.send(v2.data(), v2.size());                   // version 7
  PoseMessage nan_pose = pose(6, 1.001, 0.1);
  nan_pose.sample.position.z() = std::numeric_limits<double>::quiet_NaN();
  f.client.send_pose(nan_pose);
  PoseMessage skew = pose(6, 1.001, 0.1);
  skew.sample.orientation.coeffs() *= 1.5;
  f.client.send_pose(skew);                              // |q| = 1.5
  f.client.send_pose(pose(6, 1.001, 0.2));               // 10 cm in 1 ms
  f.client.send_pose(pose(4, 1.001, 0.1));               // old sequence
  f.client.send_pose(pose(6, 0.5, 0.1));                 // time backwards
  EXPECT_FALSE(poll_until(f.server, 9, 0.1));

  const PoseStreamCounters& c = f.server.counters();
  EXPECT_EQ(c.received, 9);
  EXPECT_EQ(c.accepted, 1);
  EXPECT_EQ(c.rejected_total(), 8);
  for (RejectReason r : {RejectReason::kBadMagic, RejectReason::kMalformed, RejectReason::kBadVersion,
                         RejectReason::kNonFinite, RejectReason::kBadQuaternion, RejectReason::kJump,
                         RejectReason::kOutOfOrder, RejectReason::kTimeNotIncreasing})
    EXPECT_EQ(c.rejected[static_cast<int>(r)], 1) << to_string(r);
  ASSERT_EQ(f.log.size(), 8u);
  EXPECT_NE(f.log[0].find("bad magic"), std::string::npos) << f.log[0];
  EXPECT_NE(f.log[0].find("holding the pose of sequence 5"), std::string::npos) << f.log[0];
  EXPECT_NE(f.log[1].find("40 bytes, expected 88"), std::string::npos) << f.log[1];
  EXPECT_NE(f.log[3].find("(sequence 6): non-finite: z = nan"), std::string::npos) << f.log[3];
  ASSERT_TRUE(f.server.last_good());
  EXPECT_EQ(f.server.last_good()->sequence, 5u);
  EXPECT_EQ(f.server.last_good()->sample.position.x(), 0.1);

  // The stream goes on after the abuse.
  f.client.send_pose(pose(7, 1.002, 0.1001));
  const auto next = poll_until(f.server, 10, 0.2);
  ASSERT_TRUE(next);
  EXPECT_EQ(next->sequence, 7u);
}

TEST(PoseStreamServer, AFloodIsReadInBoundedChunksPerPoll) {
  PoseStreamServerOptions o;
  o.max_datagrams_per_poll = 4;
  PoseStreamServer server(o);
  Client client(server.port());
  for (int i = 1; i <= 10; ++i) client.send_pose(pose(i, 0.001 * i, 0.0));
  std::this_thread::sleep_for(std::chrono::milliseconds(2));  // all ten queued (loopback is immediate)
  std::vector<StreamSample> accepted;
  server.poll(0.0, &accepted);
  EXPECT_EQ(server.counters().received, 4);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (accepted.size() < 10 && std::chrono::steady_clock::now() < deadline) {
    const long before = server.counters().received;
    server.poll(0.0, &accepted);
    EXPECT_LE(server.counters().received - before, 4);
  }
  ASSERT_EQ(accepted.size(), 10u);
  EXPECT_EQ(accepted.back().sequence, 10u);
}

TEST(PoseStreamServer, ServesAClientFromAThreadAtTheDeviceRate) {
  // The simulator side in its own thread: poll, answer each new sample.
  PoseStreamServer server;
  std::atomic<bool> stop{false};
  std::thread sim([&] {
    double t = 0.0;
    while (!stop) {
      if (auto s = server.poll(t)) server.send_feedback(Vec3(-s->sample.position.x(), 0, 0), Vec3::Zero(), t);
      t += 1e-4;
    }
  });
  Client client(server.port());
  const int n = 200;
  int answered = 0;
  for (int i = 1; i <= n; ++i) {
    client.send_pose(pose(i, 1e-3 * i, 1e-4 * i));
    // Each feedback echoes the newest accepted sequence; wait for ours.
    for (;;) {
      const auto fb = client.receive();
      ASSERT_TRUE(fb) << "no feedback for sequence " << i;
      if (fb->sequence == static_cast<std::uint64_t>(i)) {
        EXPECT_EQ(fb->force.x(), -1e-4 * i);
        ++answered;
        break;
      }
    }
  }
  stop = true;
  sim.join();
  EXPECT_EQ(answered, n);
  EXPECT_EQ(server.counters().accepted, n);
  EXPECT_EQ(server.counters().rejected_total(), 0);
}

}  // namespace
}  // namespace sflsh::teleop
