#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include <nlohmann/json.hpp>

#include "sflsh/viewer/frame_codec.hpp"
#include "sflsh/viewer/viewer_server.hpp"
#include "sflsh/viewer/web_assets.hpp"
#include "test_support.hpp"
#include "viewer_test_support.hpp"

namespace sflsh::viewer {
namespace {

ViewerFrame frame_of(const ViewerScene& s, double shift) {
  ViewerFrame f;
  f.time = shift;
  f.positions = s.rest;
  f.positions.col(0).array() += shift;
  f.displacement = VecX::Constant(s.rest.rows(), 0.004);
  f.object_poses = {Isometry(Eigen::Translation3d(0.1, 0.2, 0.3))};
  return f;
}

// Quantization bound: half a 16-bit step of the box (2 m / 65535 / 2).
constexpr double kHalfStep = 2.0 / 65535 / 2 + 1e-12;

TEST(FrameCodec, FullThenDeltaDecodeToTheFrames) {
  const ViewerScene s = test::tiny_scene();
  ViewerFrame f = frame_of(s, 0.25);
  QuantizedSkin sent, seen;
  const std::string full = encode_frame(f, quantize(f, s), s, {7, 3, true, 1}, &sent);
  DecodedFrame d = decode_frame(full, s, &seen);
  // Layout: 48-byte header, 4 × (6 + 1) skin bytes (28, aligned), one pose of 7 float32, the JSON.
  EXPECT_EQ(full.size(), 48u + 28 + 28 + d.info.size());
  EXPECT_EQ(d.kind, kFullFrame);
  EXPECT_EQ(d.number, 7u);
  EXPECT_LE((d.positions - f.positions).cwiseAbs().maxCoeff(), kHalfStep);
  EXPECT_NEAR(d.displacement[0], 0.004, 0.01 / 255 / 2 + 1e-9);
  EXPECT_NEAR(d.object_poses.at(0).translation().y(), 0.2, 1e-7);
  EXPECT_EQ(nlohmann::json::parse(d.info)["seq"], 3);
  // Only vertex 2 moves: a delta with one entry (48 + 11 bytes + padding + pose + info).
  f.positions(2, 1) += 0.1;
  const std::string delta = encode_frame(f, quantize(f, s), s, {8, 3, true, 1}, &sent);
  d = decode_frame(delta, s, &seen);
  EXPECT_EQ(d.kind, kDeltaFrame);
  EXPECT_LT(delta.size(), full.size());
  EXPECT_LE((d.positions - f.positions).cwiseAbs().maxCoeff(), kHalfStep);
  // Positions outside the box are clamped to it.
  f.positions(0, 0) = 5.0;
  d = decode_frame(encode_frame(f, quantize(f, s), s, {}, nullptr), s, &seen);
  EXPECT_DOUBLE_EQ(d.positions(0, 0), 1.0);
  sflsh::test::expect_error([&] { decode_frame(full.substr(0, 50), s, &seen); }, {"truncated"});
}

TEST(ViewerServer, ServesThePageOverHttp) {
  if (!web_assets_problem().empty()) GTEST_SKIP() << web_assets_problem();
  const WebAsset* index = find_web_asset("/?x=1");
  ASSERT_NE(index, nullptr);
  EXPECT_NE(index->body.find("importmap"), std::string::npos);
  EXPECT_NE(find_web_asset("/three/three.module.js"), nullptr);
  EXPECT_NE(find_web_asset("/src/app.js"), nullptr);
  EXPECT_EQ(find_web_asset("/nope.js"), nullptr);
}

TEST(ViewerServer, SceneFramesAndControlsRoundTrip) {
  if (!web_assets_problem().empty()) GTEST_SKIP() << web_assets_problem();
  ViewerServerOptions o;
  o.port = 0;
  o.quiet = true;
  ViewerServer server(test::tiny_scene(), o);
  EXPECT_EQ(server.url(), "http://127.0.0.1:" + std::to_string(server.port()) + "/");
  test::Client a(server.port());
  bool text = false;
  const auto scene = nlohmann::json::parse(a.read(&text));
  EXPECT_TRUE(text);
  EXPECT_EQ(scene["type"], "scene");
  EXPECT_EQ(scene["faces"], nlohmann::json({0, 1, 2, 0, 2, 3}));
  EXPECT_EQ(scene["tools"][0]["name"], "probe");

  // Controls from the driver arrive in order, with the values sent.
  a.send(R"({"type":"tool","seq":1,"t":0.0,"pos":[0,0,0],"quat":[1,0,0,0],"closure":0})");
  a.send(R"({"type":"tool","seq":2,"t":0.1,"pos":[0.01,0,0],"quat":[1,0,0,0],"closure":0.5})");
  a.send(R"({"type":"pause","seq":3,"paused":true})");
  // Malformed, a jump (1 m in 0.1 s = 10 m/s > 5 m/s), time going back, an unknown tool: all ignored.
  a.send("{garbage");
  a.send(R"({"type":"tool","seq":4,"t":0.2,"pos":[1.01,0,0],"quat":[1,0,0,0],"closure":0.5})");
  a.send(R"({"type":"tool","seq":5,"t":0.05,"pos":[0.01,0,0],"quat":[1,0,0,0],"closure":0.5})");
  a.send(R"({"type":"tool","seq":6,"t":0.3,"tool":3,"pos":[0.01,0,0],"quat":[1,0,0,0],"closure":0.5})");
  // A second client watches: its control is ignored.
  test::Client b(server.port());
  b.read();
  b.send(R"({"type":"reset","seq":1})");
  a.send(R"({"type":"step","seq":7})");
  std::vector<ControlMessage> got;
  for (int i = 0; i < 200 && got.size() < 4; ++i) {
    for (auto& m : server.poll()) got.push_back(m);
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ASSERT_EQ(got.size(), 4u);
  EXPECT_EQ(got[0].type, ControlType::kTool);
  EXPECT_EQ(got[1].pose.position.x(), 0.01);
  EXPECT_EQ(got[1].pose.closure, 0.5);
  EXPECT_EQ(got[2].type, ControlType::kPause);
  EXPECT_TRUE(got[2].paused);
  EXPECT_EQ(got[3].type, ControlType::kStep);
  EXPECT_EQ(got[3].seq, 7u);
  EXPECT_EQ(server.counters().controls_rejected, 5);
  EXPECT_EQ(server.counters().controls_accepted, 4);
  EXPECT_EQ(server.num_clients(), 2);

  // A published frame reaches both clients; the driver's echoes seq 7.
  const ViewerScene& s = server.scene();
  const ViewerFrame f = frame_of(s, 0.125);
  server.publish(f);
  for (test::Client* c : {&a, &b}) {
    QuantizedSkin state;
    const DecodedFrame d = decode_frame(c->read(&text), s, &state);
    EXPECT_FALSE(text);
    EXPECT_LE((d.positions - f.positions).cwiseAbs().maxCoeff(), kHalfStep);
    const auto info = nlohmann::json::parse(d.info);
    EXPECT_EQ(info["seq"], 7);
    EXPECT_EQ(info["driver"], c == &a);
    EXPECT_EQ(info["clients"], 2);
  }
}

TEST(ViewerServer, SlowClientGetsTheLatestFrameNotABacklog) {
  if (!web_assets_problem().empty()) GTEST_SKIP() << web_assets_problem();
  ViewerServerOptions o;
  o.port = 0;
  o.quiet = true;
  // 100k vertices: 0.7 MB per frame, far more than loopback socket buffers hold for 200 frames.
  ViewerScene big = test::tiny_scene();
  big.rest = Points::Random(100000, 3) * 0.5;
  big.body_offsets = {0, 100000};
  ViewerServer server(big, o);
  test::Client a(server.port());
  a.read();  // scene
  // 200 frames published while the client reads nothing: publish never blocks
  // (a blocking publish would never return here: the client reads only after).
  for (int i = 1; i <= 200; ++i) server.publish(frame_of(server.scene(), i * 1e-3));
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  // Whatever was in flight, the client ends on frame 200 after few messages.
  QuantizedSkin state;
  int messages = 0;
  DecodedFrame d;
  do {
    d = decode_frame(a.read(), server.scene(), &state);
    ++messages;
  } while (d.number != 200u);
  EXPECT_LT(messages, 200);
  EXPECT_NEAR(d.time, 0.2, 1e-12);
}

TEST(ViewerServer, RejectsABadBindAddress) {
  if (!web_assets_problem().empty()) GTEST_SKIP() << web_assets_problem();
  ViewerServerOptions o;
  o.bind = "not-an-address";
  o.port = 0;
  sflsh::test::expect_error([&] { ViewerServer s(test::tiny_scene(), o); }, {"bind address", "not-an-address"});
}

}  // namespace
}  // namespace sflsh::viewer
