// The contact terms of a result: a ball resting on the small box avatar
// stores its weight at the last frame, contacts survive a write and read with
// every value in its place, files without /contacts read as no contacts, and
// a damaged /contacts group is one error naming the file and the dataset.
#include <gtest/gtest.h>

#include <hdf5.h>

#include <cmath>
#include <functional>

#include "sflsh/core/error.hpp"
#include "sflsh/io/hdf5_file.hpp"
#include "sflsh/scene/result_contacts.hpp"
#include "sflsh/scene/result_file.hpp"
#include "sflsh/scene/scene_description.hpp"
#include "sflsh/scene/scene_run.hpp"
#include "scene/box_avatar_fixture.hpp"
#include "test_support.hpp"

using namespace sflsh;

namespace {

using ResultContacts = test::BoxAvatarScene;

TEST_F(ResultContacts, ABallRestingOnTheBodyStoresItsWeight) {
  // A 0.2 kg ball set 3 mm above the box's top (y = 0.03 m) falls, lands and
  // rests (as scene_run_test's ball); "far" never touches anything.
  const double g = 9.81, m = 0.2, r = 0.05;
  SceneDescription sc = read_scene_description(write_scene(R"(
solver: {dt: 1/60, seconds: 1.5, newton_iters: 4, line_search: true}
output: {fps: 10}
bodies:
  - {name: base, avatar: box.h5, bones: kinematic}
objects:
  - name: ball
    shape: {type: sphere, radius: 0.05}
    kind: dynamic
    mass: 0.2
    position: [0.0, 0.083, 0.0]
  - name: far
    shape: {type: box, size: [0.1, 0.05, 0.02]}
    kind: kinematic
    keyframes: [{time: 0, position: [2.0, 0.5, 0]}]
)"));
  SceneRunOptions opt;
  opt.progress = false;
  SceneContactStats stats;
  const SimulationResult res = run_scene(sc, opt, &stats);
  ASSERT_EQ(res.contacts.size(), 2u);
  const ContactTrack &ball = res.contacts[0], &far = res.contacts[1];
  EXPECT_EQ(ball.term, "contact:ball");
  EXPECT_EQ(ball.body, "base");
  EXPECT_EQ(far.term, "contact:far");
  ASSERT_EQ(ball.frames.size(), res.frame_time.size());
  ASSERT_EQ(res.frame_time.size(), 16u);
  // At rest on the body after 1.5 s the contact carries the ball's weight,
  // pushing the body down: f = (0, −m g, 0). 2 %: what is left of the landing
  // after 1.4 s of penalty contact (the ball's vertical speed is ~mm/s; the
  // same tolerance as scene_run_test's ball); the sideways part is friction
  // and symmetry noise, far below 1 % of m g.
  const ContactFrame& last = ball.frames.back();
  EXPECT_NEAR(last.force.y(), -m * g, 0.02 * m * g);
  EXPECT_LT(std::hypot(last.force.x(), last.force.z()), 0.01 * m * g);
  // The stored frame is the last step's report, as the contact figures have it.
  ASSERT_FALSE(stats.pairs.empty());
  EXPECT_EQ(stats.pairs[0].term, "contact:ball");
  EXPECT_LT((last.force - stats.pairs[0].last_force).norm(), 1e-12);
  // It acts on the top face below the ball: y within 1 cm of 0.03, x and z
  // well inside the ball's footprint (radius 5 cm; the contact is centred).
  EXPECT_NEAR(last.point.y(), 0.03, 0.01);
  EXPECT_LT(std::hypot(last.point.x(), last.point.z()), 0.2 * r);
  EXPECT_GT(last.max_penetration, 0.0);
  EXPECT_LT(last.max_penetration, 0.01);
  EXPECT_GT(last.active, 0);
  // Before any step (frame 0) nothing touches; the ball has landed by 0.5 s.
  EXPECT_EQ(ball.frames.front().force, Vec3::Zero());
  EXPECT_EQ(ball.frames.front().active, 0);
  EXPECT_GT(ball.frames[5].active, 0);
  // "far" never touches: zero force every frame, drawn at the object's position.
  for (const ContactFrame& f : far.frames) {
    EXPECT_EQ(f.force, Vec3::Zero());
    EXPECT_EQ(f.active, 0);
    EXPECT_LT((f.point - Vec3(2.0, 0.5, 0)).norm(), 1e-12);
  }
  // The result file keeps them.
  const std::string path = (dir_ / "ball.h5").string();
  write_simulation_result(res, path);
  const SimulationResult back = read_simulation_result(path);
  ASSERT_EQ(back.contacts.size(), 2u);
  EXPECT_EQ(back.contacts[0].frames.back().force, last.force);
  EXPECT_EQ(back.contacts[0].frames.back().point, last.point);
}

/// One body (a triangle) over 3 frames with two contacts whose every value
/// differs per contact, per frame and per field.
SimulationResult contact_result() {
  SimulationResult r;
  r.avatar = "a.h5";
  r.motion = "scene.yaml";
  r.dt = 1.0 / 60;
  r.faces.resize(1, 3);
  r.faces << 0, 1, 2;
  r.surface_rest = Points::Random(3, 3);
  r.contacts = {{"contact:floor", "alice", {}}, {"self_contact", "alice", {}}};
  for (int f = 0; f < 3; ++f) {
    r.frame_time.push_back(f / 30.0);
    r.frame_step_ms.push_back(1.0);
    r.frame_positions.push_back(Points::Zero(3, 3));
    r.frame_displacement.push_back(Points::Zero(3, 3));
    r.frame_joints.push_back(Points::Zero(24, 3));
    r.frame_reduced.push_back(VecX::Zero(2));
    r.frame_target_pelvis.push_back(Vec3::Zero());
    for (int c = 0; c < 2; ++c) {
      const double k = 1 + f + 10 * c;
      r.contacts[size_t(c)].frames.push_back(
          {Vec3(0.5 * k, -1.25 * k, 2.0 + k), Vec3(-0.01 * k, 0.02 * k, 0.3 + 0.001 * k), 1e-4 * k, int(7 * k)});
    }
  }
  r.num_frames = 3;
  r.step_time = {1 / 60.0};
  r.step_energy = r.step_grad_norm = r.step_decrement = r.step_ms = {1.0};
  r.step_outcome = {0};
  return r;
}

TEST(ResultContactsFile, RoundTripKeepsEveryValueInItsPlace) {
  test::TempDir tmp;
  const SimulationResult r = contact_result();
  write_simulation_result(r, tmp.file("c.h5"));
  const SimulationResult b = read_simulation_result(tmp.file("c.h5"));
  ASSERT_EQ(b.contacts.size(), 2u);
  for (size_t c = 0; c < 2; ++c) {
    EXPECT_EQ(b.contacts[c].term, r.contacts[c].term);
    EXPECT_EQ(b.contacts[c].body, r.contacts[c].body);
    ASSERT_EQ(b.contacts[c].frames.size(), 3u);
    for (size_t f = 0; f < 3; ++f) {
      const ContactFrame &x = b.contacts[c].frames[f], &y = r.contacts[c].frames[f];
      EXPECT_EQ(x.force, y.force) << "contact " << c << " frame " << f;  // float64: exact
      EXPECT_EQ(x.point, y.point) << "contact " << c << " frame " << f;
      EXPECT_EQ(x.max_penetration, y.max_penetration) << "contact " << c << " frame " << f;
      EXPECT_EQ(x.active, y.active) << "contact " << c << " frame " << f;
    }
  }
  // The layout: one group per contact, a row per frame.
  io::Hdf5File f(tmp.file("c.h5"), io::Hdf5File::Mode::Read);
  EXPECT_EQ(f.read_string("/contacts/1/term"), "self_contact");
  EXPECT_EQ(f.shape("/contacts/0/force"), (std::vector<std::int64_t>{3, 3}));
  EXPECT_EQ(f.shape("/contacts/1/max_penetration"), (std::vector<std::int64_t>{3}));
  EXPECT_EQ(f.read_matrix("/contacts/1/active_samples")(2, 0), 7 * 13);
  // inspect's line: the peak is the last frame's (k = 13 for self_contact: |(6.5, −16.25, 15)| = 23.05 N).
  EXPECT_NE(describe_contacts(b).find("contact self_contact on alice: peak force 23.05 N at t = 0.067 s, max "
                                      "penetration 1.30 mm, up to 91 active samples\n"),
            std::string::npos)
      << describe_contacts(b);
}

TEST(ResultContactsFile, AFileWithoutContactsReadsAsNone) {
  test::TempDir tmp;
  SimulationResult r = contact_result();
  r.contacts.clear();
  write_simulation_result(r, tmp.file("old.h5"));
  {
    io::Hdf5File f(tmp.file("old.h5"), io::Hdf5File::Mode::Read);
    EXPECT_FALSE(f.has("/contacts"));  // the layout of files written before contacts were stored
  }
  const SimulationResult b = read_simulation_result(tmp.file("old.h5"));
  EXPECT_TRUE(b.contacts.empty());
  EXPECT_EQ(b.num_frames, 3);
  EXPECT_EQ(describe_contacts(b), "");
}

/// Replaces dataset `name` of the file at `path` by `rows` × `cols` values of `value`.
void replace_dataset(const std::string& path, const std::string& name, hsize_t rows, hsize_t cols, double value) {
  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  ASSERT_GE(file, 0);
  ASSERT_GE(H5Ldelete(file, name.c_str(), H5P_DEFAULT), 0);
  const hsize_t dims[2] = {rows, cols};
  const hid_t space = H5Screate_simple(cols ? 2 : 1, dims, nullptr);
  const hid_t set = H5Dcreate2(file, name.c_str(), H5T_NATIVE_DOUBLE, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  const std::vector<double> values(rows * (cols ? cols : 1), value);
  H5Dwrite(set, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data());
  H5Dclose(set);
  H5Sclose(space);
  H5Fclose(file);
}

TEST(ResultContactsFile, DamagedContactsAreOneErrorNamingFileAndDataset) {
  test::TempDir tmp;
  const std::string p = tmp.file("bad.h5");
  auto expect_rejected = [&](const std::function<void()>& damage, std::initializer_list<std::string> fragments) {
    write_simulation_result(contact_result(), p);
    damage();
    test::expect_error([&] { read_simulation_result(p); }, fragments);
  };
  // Truncated: 2 frames of force for 3 frames.
  expect_rejected([&] { replace_dataset(p, "/contacts/1/force", 2, 3, 1.0); }, {"bad.h5", "/contacts/1/force"});
  // Misshapen: force without its 3 components.
  expect_rejected([&] { replace_dataset(p, "/contacts/0/point", 3, 2, 1.0); }, {"bad.h5", "/contacts/0/point"});
  // Missing dataset.
  expect_rejected(
      [&] {
        const hid_t f = H5Fopen(p.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
        H5Ldelete(f, "/contacts/0/max_penetration", H5P_DEFAULT);
        H5Fclose(f);
      },
      {"bad.h5", "/contacts/0/max_penetration", "missing"});
  // Values no contact has.
  expect_rejected([&] { replace_dataset(p, "/contacts/1/active_samples", 3, 0, 2.5); },
                  {"bad.h5", "/contacts/1/active_samples", "whole number"});
  expect_rejected([&] { replace_dataset(p, "/contacts/0/max_penetration", 3, 0, -0.1); },
                  {"bad.h5", "/contacts/0/max_penetration", ">= 0"});
  expect_rejected([&] { replace_dataset(p, "/contacts/0/force", 3, 3, NAN); }, {"bad.h5", "/contacts/0/force"});
  // A gap in the groups.
  expect_rejected(
      [&] {
        const hid_t f = H5Fopen(p.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
        H5Lmove(f, "/contacts/1", f, "/contacts/2", H5P_DEFAULT, H5P_DEFAULT);
        H5Fclose(f);
      },
      {"bad.h5", "/contacts/2", "missing /contacts/1"});
}

TEST(ResultContactsFile, WriterRefusesFramesThatDoNotFit) {
  test::TempDir tmp;
  SimulationResult r = contact_result();
  r.contacts[1].frames.pop_back();
  test::expect_error([&] { write_simulation_result(r, tmp.file("w.h5")); },
                     {"w.h5", "contact 'self_contact' on 'alice' has 2 frames for 3 frames"});
  r = contact_result();
  r.contacts[0].frames[1].force.y() = NAN;
  test::expect_error([&] { write_simulation_result(r, tmp.file("w.h5")); },
                     {"w.h5", "frame 1", "contact 'contact:floor' on 'alice'", "non-finite"});
}

}  // namespace
