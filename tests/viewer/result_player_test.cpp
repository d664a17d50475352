// Playback (`sflsh view`): the frame shown at time t is the result file's
// frame at time t (the last frame at or before t), through the server and a
// WebSocket client, to within the 16-bit quantization of positions.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "sflsh/scene/result_file.hpp"
#include "sflsh/viewer/result_player.hpp"
#include "sflsh/viewer/viewer_server.hpp"
#include "sflsh/viewer/web_assets.hpp"
#include "test_support.hpp"
#include "viewer_test_support.hpp"

namespace sflsh::viewer {
namespace {

// Four frames 0.1 s apart; frame k's skin is the rest shape moved by (k cm, 2k cm, 0) and
// its displacement is (k mm, 0, 0) per vertex.
SimulationResult four_frames() {
  const ViewerScene s = test::tiny_scene();
  SimulationResult r;
  r.avatar = "tiny";
  r.motion = "none";
  r.dt = 0.01;
  r.faces = s.faces;
  r.surface_rest = s.rest;
  for (int k = 0; k < 4; ++k) {
    r.frame_time.push_back(0.1 * k);
    r.frame_step_ms.push_back(1.0);
    Points p = s.rest;
    p.col(0).array() += 0.01 * k;
    p.col(1).array() += 0.02 * k;
    r.frame_positions.push_back(p);
    Points u = Points::Zero(s.rest.rows(), 3);
    u.col(0).array() = 0.001 * k;
    r.frame_displacement.push_back(u);
    r.frame_joints.push_back(Points::Zero(24, 3));
    r.frame_reduced.push_back(VecX::Zero(2));
    r.add_step(0.1 * k, StepReport{});
  }
  r.num_frames = 4;
  return r;
}

TEST(ResultPlayer, FrameAtTimeIsTheLastFrameAtOrBefore) {
  const std::vector<double> t = {0.0, 0.1, 0.2, 0.3};
  EXPECT_EQ(frame_at(t, -1.0), 0);
  EXPECT_EQ(frame_at(t, 0.0), 0);
  EXPECT_EQ(frame_at(t, 0.0999), 0);
  EXPECT_EQ(frame_at(t, 0.1), 1);
  EXPECT_EQ(frame_at(t, 0.25), 2);
  EXPECT_EQ(frame_at(t, 7.0), 3);
}

TEST(ResultPlayer, ControlsMoveThePlaybackClock) {
  const SimulationResult r = four_frames();
  ResultPlayer p(r);
  EXPECT_TRUE(p.paused());
  ControlMessage m;
  m.type = ControlType::kPause;
  m.paused = false;
  p.apply(m);
  m.type = ControlType::kSpeed;
  m.value = 0.5;
  p.apply(m);
  p.advance(0.4);  // 0.2 s of result time
  EXPECT_NEAR(p.time(), 0.2, 1e-12);
  EXPECT_EQ(p.frame(), 2);
  p.advance(10);  // past the end: holds the last frame, paused
  EXPECT_EQ(p.frame(), 3);
  EXPECT_TRUE(p.paused());
  m.type = ControlType::kReset;
  p.apply(m);
  m.type = ControlType::kStep;
  p.apply(m);
  EXPECT_EQ(p.frame(), 1);
  m.type = ControlType::kTool;
  EXPECT_FALSE(p.apply(m));
}

TEST(ResultPlayer, TheFrameShownAtTimeTIsTheFilesFrameAtT) {
  if (!web_assets_problem().empty()) GTEST_SKIP() << web_assets_problem();
  sflsh::test::TempDir dir;
  write_simulation_result(four_frames(), dir.file("r.h5"));
  const SimulationResult r = read_simulation_result(dir.file("r.h5"));
  ViewerServerOptions o;
  o.port = 0;
  o.quiet = true;
  ViewerServer server(viewer_scene(r, {}, 0.05, 0.001), o);
  ResultPlayer player(r);
  test::Client client(server.port());
  client.read();  // the scene
  QuantizedSkin state;
  const Vec3 size = server.scene().box_max - server.scene().box_min;
  for (const double t : {0.0, 0.15, 0.2, 0.29, 0.3}) {
    ControlMessage seek;
    seek.type = ControlType::kSeek;
    seek.value = t;
    player.apply(seek);
    server.publish(player.current());
    const DecodedFrame d = decode_frame(client.read(), server.scene(), &state);
    // The frame at t, by hand: floor(t / 0.1) (t on a frame time shows that frame).
    const int k = int(std::floor(t / 0.1 + 1e-9));
    Points expected = server.scene().rest;  // frame 0's skin
    expected.col(0).array() += 0.01 * k;
    expected.col(1).array() += 0.02 * k;
    for (int c = 0; c < 3; ++c)
      EXPECT_LE((d.positions.col(c) - expected.col(c)).cwiseAbs().maxCoeff(), size[c] / 65535 / 2 + 1e-7) << "t " << t;
    EXPECT_NEAR(d.displacement[0], 0.001 * k, 0.003 / 255) << "t " << t;  // legend 3 mm in 8 bits
    EXPECT_EQ(nlohmann::json::parse(d.info)["frame"], k) << "t " << t;
    EXPECT_NEAR(d.time, t, 1e-12);
  }
}

}  // namespace
}  // namespace sflsh::viewer
