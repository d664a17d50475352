// A checkpoint taken in the middle of a press (sim/state_file.hpp): the
// contact patch's displacement δu and its history are state the term carries
// from step to step, so the file holds them and a resumed run goes on as the
// uninterrupted one. Bad caches in a file are refused naming the file and the
// dataset.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "scene/box_avatar_fixture.hpp"
#include "sflsh/io/hdf5_file.hpp"
#include "sflsh/scene/scene_description.hpp"
#include "sflsh/scene/scene_session.hpp"
#include "sflsh/sim/state_file.hpp"
#include "test_support.hpp"

using namespace sflsh;

namespace {

/// A kinematic 5 mm sphere pressed 1 cm into the box's top by 0.2 s, under a patch.
const char* kObjectPressScene = R"(
solver: {dt: 1/250, seconds: 1, damping: 0.01}
contact: {patch: true, friction: 0}
bodies:
  - {name: base, avatar: box.h5, bones: kinematic}
objects:
  - name: probe
    shape: {type: sphere, radius: 0.005}
    kind: kinematic
    keyframes:
      - {time: 0.0, position: [0.0, 0.040, 0.0]}
      - {time: 0.2, position: [0.0, 0.020, 0.0]}
)";

SceneSessionOptions quiet() {
  SceneSessionOptions o;
  o.progress = false;
  return o;
}

/// The saved states of the caches that carry one (by model term index, empty: none).
std::vector<std::vector<double>> saved_caches(const SceneSession& s) {
  std::vector<std::vector<double>> out;
  for (const std::unique_ptr<TermCache>& c : s.simulator().scene_state().carried_caches())
    out.push_back(c ? c->saved_state() : std::vector<double>());
  return out;
}

class CheckpointResume : public test::BoxAvatarScene {
 protected:
  /// `steps` steps of the press, then its state written to DIR/NAME.
  std::string checkpoint_after(int steps, const std::string& name) {
    SceneSession s(scene(), quiet());
    for (int i = 0; i < steps; ++i) s.advance();
    const std::string path = (dir_ / name).string();
    write_state(path, s.simulator().model(), s.simulator().scene_state());
    return path;
  }
  SceneDescription scene() { return read_scene_description(write_scene(kObjectPressScene)); }
};

}  // namespace

TEST_F(CheckpointResume, AMidPressCheckpointResumesWithThePatchBitForBit) {
  SceneSession whole(scene(), quiet());
  for (int i = 0; i < 40; ++i) whole.advance();
  // The patch holds a dent now: its history is non-empty.
  size_t saved = 0;
  for (const std::vector<double>& v : saved_caches(whole)) saved += v.size();
  ASSERT_GT(saved, 0u) << "the probe should have a patch with a displacement by now";
  const std::string path = (dir_ / "mid_press.h5").string();
  write_state(path, whole.simulator().model(), whole.simulator().scene_state());

  SceneSession resumed(scene(), quiet()), bodies_only(scene(), quiet());
  const State state = read_state(path, resumed.simulator().model());
  resumed.resume(state, path);
  // The same state without the patch's history (what a checkpoint held before).
  State without;
  without.time = state.time;
  without.bodies = state.bodies;
  bodies_only.resume(without, path);
  EXPECT_EQ(saved_caches(resumed), saved_caches(whole)) << "the restored history is the saved one, exactly";

  for (int i = 0; i < 10; ++i) {
    whole.advance();
    resumed.advance();
    bodies_only.advance();
  }
  const State& w = whole.simulator().scene_state();
  const State& r = resumed.simulator().scene_state();
  EXPECT_EQ(resumed.time(), whole.time());
  EXPECT_EQ(r.bodies[0].q.z, w.bodies[0].q.z);
  EXPECT_EQ(r.bodies[0].q_prev.z, w.bodies[0].q_prev.z);
  EXPECT_EQ(resumed.body_surface(0), whole.body_surface(0));
  EXPECT_EQ(saved_caches(resumed), saved_caches(whole));
  // Without the history the dent pops: the skin differs by far more than rounding.
  const double popped = (bodies_only.body_surface(0) - whole.body_surface(0)).cwiseAbs().maxCoeff();
  EXPECT_GT(popped, 1e-6) << "a resume without the patch's history should not match";
}

TEST_F(CheckpointResume, BadCachesAreRefusedNamingTheFileAndTheDataset) {
  const std::string good = checkpoint_after(40, "good.h5");
  SceneSession s(scene(), quiet());
  const Model& model = s.simulator().model();
  int patch_term = -1, elastic_term = -1;
  for (size_t j = 0; j < model.terms().size(); ++j) {
    if (model.terms()[j].term->name() == "contact:probe") patch_term = int(j);
    if (model.terms()[j].term->name() == "elastic") elastic_term = int(j);
  }
  ASSERT_GE(patch_term, 0);
  ASSERT_GE(elastic_term, 0);
  // A copy of the good file with the patch's cache replaced.
  auto crafted = [&](const std::string& name, const std::string& term_name, const std::vector<double>& values,
                     int term = -1, int version = kStateFormatVersion) {
    const io::Hdf5File in(good, io::Hdf5File::Mode::Read);
    const std::string path = (dir_ / name).string();
    io::Hdf5File f(path, io::Hdf5File::Mode::Write);
    f.write_scalar("/meta/format_version", std::int64_t(version));
    f.write_string("/meta/kind", "sflsh state");
    f.write_scalar("/state/time", in.read_scalar("/state/time"));
    f.write_strings("/state/bodies", in.read_strings("/state/bodies"));
    for (const char* d : {"bones", "bones_prev"}) f.write_matrix(std::string("/state/0/") + d, in.read_matrix(std::string("/state/0/") + d));
    for (const char* d : {"z", "z_prev"}) {
      const std::vector<double> v = in.read_nd(std::string("/state/0/") + d, {-1});
      f.write_nd(std::string("/state/0/") + d, v.data(), {std::int64_t(v.size())});
    }
    const int j = term >= 0 ? term : patch_term;
    f.write_nd("/state/caches/terms", &j, {1});
    const std::string g = "/state/caches/" + std::to_string(j) + "/";
    f.write_string(g + "name", term_name);
    f.write_nd(g + "values", values.data(), {std::int64_t(values.size())});
    f.commit();
    return path;
  };
  std::vector<double> one_node(16, 0.0);  // a node, then δu, d_t, δu_next, d_next, du_back_next
  one_node[0] = 5;
  // The good file's values read back into a crafted copy resume (the helper is sound).
  const io::Hdf5File in(good, io::Hdf5File::Mode::Read);
  const std::string g = "/state/caches/" + std::to_string(patch_term) + "/values";
  ASSERT_TRUE(in.has(g));
  EXPECT_NO_THROW(read_state(crafted("same.h5", "contact:probe", in.read_nd(g, {-1})), model));

  const std::string renamed = crafted("renamed.h5", "contact:other", one_node);
  test::expect_error([&] { read_state(renamed, model); }, {renamed, "name is 'contact:other'", "contact:probe"});
  std::vector<double> seventeen(17, 0.0);
  const std::string short_row = crafted("short_row.h5", "contact:probe", seventeen);
  test::expect_error([&] { read_state(short_row, model); }, {short_row, "values", "not a multiple of 16"});
  // Format 2 kept 13 values per node: its caches are refused, even when their count would parse.
  std::vector<double> sixteen_old_nodes(13 * 16, 0.0);
  for (int i = 0; i < 16; ++i) sixteen_old_nodes[size_t(13 * i)] = i;
  const std::string old_layout = crafted("format2.h5", "contact:probe", sixteen_old_nodes, -1, 2);
  test::expect_error([&] { read_state(old_layout, model); }, {old_layout, "format_version is 2", "older layout"});
  std::vector<double> far = one_node;
  far[0] = 1e6;
  const std::string far_node = crafted("far_node.h5", "contact:probe", far);
  test::expect_error([&] { read_state(far_node, model); }, {far_node, "names node 1e+06", "below"});
  std::vector<double> nan = one_node;
  nan[4] = std::nan("");
  const std::string not_finite = crafted("nan.h5", "contact:probe", nan);
  test::expect_error([&] { read_state(not_finite, model); }, {not_finite, "/values", "non-finite value at flat index 4"});
  const std::string beyond = crafted("beyond.h5", "contact:probe", one_node, 99);
  test::expect_error([&] { read_state(beyond, model); }, {beyond, "/state/caches/terms[0] is 99"});
  const std::string keeps_none = crafted("elastic.h5", "elastic", one_node, elastic_term);
  test::expect_error([&] { read_state(keeps_none, model); }, {keeps_none, "/state/caches/" + std::to_string(elastic_term) + "/values", "carries no state"});
}

namespace {

/// The box pinch (box_avatar_fixture.hpp) as written, and with the gripper
/// coupled (a dynamic tool body, in the State) pulling through a contact patch.
std::string pinch_scene(bool coupled) {
  std::string text = test::kBoxPinchScene;
  if (!coupled) return text;
  text = "contact: {patch: true, friction: 0}\n" + text;
  const std::string grasp = "    grasp:\n";
  text.insert(text.find(grasp), "    coupling: {stiffness: 2000, mass: 0.05, max_force: 100}\n");
  return text;
}

std::vector<std::vector<int>> held_points(const SceneSession& s) {
  std::vector<std::vector<int>> out;
  for (int t = 0; t < s.num_tools(); ++t) out.push_back({s.tool_state(t).anchors});
  return out;
}

}  // namespace

/// A checkpoint taken while the gripper holds the skin (after its grasp, in
/// the lift) resumes with the grasp: the run goes on, releases at 0.25 s and
/// ends as the uninterrupted one, bit for bit. Resumed without the grasp,
/// the skin drops back and the runs part.
TEST_F(CheckpointResume, AToolsGraspResumesBitForBit) {
  for (bool coupled : {false, true}) {
    SCOPED_TRACE(coupled ? "coupled gripper through a patch" : "kinematic gripper");
    const SceneDescription sc = read_scene_description(write_scene(pinch_scene(coupled)));
    SceneSession whole(sc, quiet());
    for (int i = 0; i < 12; ++i) whole.advance();
    ASSERT_GT(whole.tool_state(0).anchors, 0) << "the gripper should hold the skin by 0.12 s";
    const std::string path = (dir_ / "holding.h5").string();
    whole.write_checkpoint(path);

    SceneSession resumed(sc, quiet());
    resumed.resume(path);
    EXPECT_EQ(resumed.steps_done(), 12);
    for (int i = 0; i < 6; ++i) whole.advance(), resumed.advance();
    EXPECT_EQ(held_points(resumed), held_points(whole)) << "still holding after the resume";
    const auto lifted = whole.body_surface(0);  // at 0.18 s
    while (whole.steps_done() < whole.total_steps()) whole.advance(), resumed.advance();
    EXPECT_EQ(resumed.time(), whole.time());
    EXPECT_EQ(resumed.simulator().scene_state().bodies[0].q.z, whole.simulator().scene_state().bodies[0].q.z);
    EXPECT_EQ(resumed.body_surface(0), whole.body_surface(0));
    EXPECT_EQ(resumed.tool_state(0).pose.matrix(), whole.tool_state(0).pose.matrix());
    // The resumed run's events: the release alone (the grasp was before it).
    ASSERT_EQ(resumed.tool_events().size(), 1u);
    EXPECT_EQ(resumed.tool_events()[0].kind, "release");
    EXPECT_EQ(resumed.tool_events()[0].time, whole.tool_events().back().time);

    // The same file without the grasp: the skin is let go at the resume.
    const std::string let_go = (dir_ / "let_go.h5").string();
    {
      const io::Hdf5File in(path, io::Hdf5File::Mode::Read);
      io::Hdf5File f(let_go, io::Hdf5File::Mode::Write);
      f.write_scalar("/meta/format_version", std::int64_t(kStateFormatVersion));
      f.write_string("/meta/kind", "sflsh state");
      f.write_scalar("/state/time", in.read_scalar("/state/time"));
      f.write_strings("/state/bodies", in.read_strings("/state/bodies"));
      for (int b = 0; b < int(in.read_strings("/state/bodies").size()); ++b) {
        const std::string g = "/state/" + std::to_string(b) + "/";
        for (const char* d : {"bones", "bones_prev"}) f.write_matrix(g + d, in.read_matrix(g + d));
        for (const char* d : {"z", "z_prev"}) {
          const std::vector<double> v = in.read_nd(g + d, {-1});
          f.write_nd(g + d, v.data(), {std::int64_t(v.size())});
        }
      }
      f.write_strings("/tools/names", {"gripper"});
      f.write_scalar("/tools/0/bodies", std::int64_t(1));
      f.commit();
    }
    SceneSession dropped(sc, quiet());
    dropped.resume(let_go);
    EXPECT_EQ(dropped.tool_state(0).anchors, 0);
    for (int i = 0; i < 6; ++i) dropped.advance();
    EXPECT_GT((dropped.body_surface(0) - lifted).cwiseAbs().maxCoeff(), 1e-4) << "the skin should drop back";
  }
}

TEST_F(CheckpointResume, AToolScenesCheckpointIsCheckedAgainstTheScene) {
  const SceneDescription sc = read_scene_description(write_scene(pinch_scene(false)));
  SceneSession s(sc, quiet());
  for (int i = 0; i < 12; ++i) s.advance();
  const std::string good = (dir_ / "good.h5").string();
  s.write_checkpoint(good);
  // A State alone holds no grasp.
  const State state = read_state(good, s.simulator().model());
  test::expect_error([&] { SceneSession(sc, quiet()).resume(state, good); },
                     {good, "holds no tool's grasp", "resume from the checkpoint file"});
  // A copy of the file with its tools' part rewritten.
  auto crafted = [&](const std::string& name, const std::function<void(io::Hdf5File&)>& tools) {
    const std::string path = (dir_ / name).string();
    write_state(path, s.simulator().model(), s.simulator().scene_state(), tools);
    return path;
  };
  const std::string none = crafted("none.h5", nullptr);
  test::expect_error([&] { SceneSession(sc, quiet()).resume(none); }, {none, "holds no tools' state", "1 tool(s)"});
  const std::string renamed = crafted("renamed.h5", [](io::Hdf5File& f) {
    f.write_strings("/tools/names", {"pliers"});
    f.write_scalar("/tools/0/bodies", std::int64_t(1));
  });
  test::expect_error([&] { SceneSession(sc, quiet()).resume(renamed); },
                     {renamed, "/tools/names[0] is 'pliers'", "'gripper'"});
  const std::string two_bodies = crafted("bodies.h5", [](io::Hdf5File& f) {
    f.write_strings("/tools/names", {"gripper"});
    f.write_scalar("/tools/0/bodies", std::int64_t(2));
  });
  test::expect_error([&] { SceneSession(sc, quiet()).resume(two_bodies); }, {two_bodies, "/tools/0/bodies is 2"});
  auto holding = [&](const std::string& name, int point, double offset) {
    return crafted(name, [=](io::Hdf5File& f) {
      f.write_strings("/tools/names", {"gripper"});
      f.write_scalar("/tools/0/bodies", std::int64_t(1));
      f.write_nd("/tools/0/0/points", &point, {1});
      MatXr o(1, 3);
      o << 0.001, offset, 0.0;
      f.write_matrix("/tools/0/0/offsets", o);
    });
  };
  const std::string far = holding("far.h5", 100000, 0.0);
  test::expect_error([&] { SceneSession(sc, quiet()).resume(far); }, {far, "/tools/0/0/points[0] is 100000", "skin vertices"});
  const std::string nan = holding("nan.h5", 3, std::nan(""));
  test::expect_error([&] { SceneSession(sc, quiet()).resume(nan); }, {nan, "/tools/0/0/offsets"});
  // The helper is sound: one anchor held on a skin vertex resumes.
  SceneSession one(sc, quiet());
  one.resume(holding("one.h5", 3, -0.002));
  EXPECT_EQ(one.steps_done(), 12);
  one.advance();
  EXPECT_EQ(one.tool_state(0).anchors, 1);
}
