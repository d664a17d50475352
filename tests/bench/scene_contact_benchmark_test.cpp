// The contact benchmark of a scene file (bench-contact --scene) on the small
// box avatar (6 cm of 1 cm cells, top at y = 0.03 m, 6 handles): a 1 cm ball
// lowered from 1.5 cm above the top to 5 mm into it by 0.2 s and held to 0.3 s,
// dt 1/100, gravity off, the reduced solver with its contact patch. The full
// FEM's and the reduced run's figures are those of `simulate --solver full`
// and `simulate` on the same scene; the depth is the ball's travel since first
// contact (5 mm less the travel before the first step that reports it).
#include "sflsh/bench/scene_contact_benchmark.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "scene/box_avatar_fixture.hpp"
#include "sflsh/core/progress.hpp"
#include "sflsh/reference/scene_reference_run.hpp"
#include "sflsh/scene/scene_description.hpp"
#include "sflsh/scene/scene_run.hpp"
#include "sflsh/scene/scene_session.hpp"
#include "test_support.hpp"

using namespace sflsh;

namespace {

using SceneContactBench = test::BoxAvatarScene;

std::string ball_scene(const std::string& kind, const std::string& pose) {
  return R"(solver: {dt: 1/100, seconds: 0.3, gravity: [0, 0, 0]}
contact: {friction: 0, patch: {radius: 0.02}}
output: {fps: 20}
bodies:
  - {name: base, avatar: box.h5, motion: none, bones: kinematic}
objects:
  - name: ball
    shape: {type: sphere, radius: 0.01}
    kind: )" + kind + "\n" + pose;
}

const std::string kLowered = R"(    keyframes:
      - {time: 0.0, position: [0.0, 0.045, 0.0]}
      - {time: 0.2, position: [0.0, 0.035, 0.0]}
)";

SceneContactBenchSettings quiet() {
  SceneContactBenchSettings s;
  s.progress = false;
  return s;
}

}  // namespace

// A kinematic tool without a shape that grasps (it lifts the top by 3 mm and
// lets go): compared by the force on the tool, per step the |force| of
// `simulate --solver full`'s tool and of the reduced session's tool state.
TEST_F(SceneContactBench, AGraspingToolIsComparedByTheForceOnTheTool) {
  const SceneDescription sc = read_scene_description(write_scene(test::kBoxPinchScene));
  Progress::set_quiet(true);
  const SceneContactBenchResult r = run_scene_contact_bench(sc, quiet());
  std::vector<double> full;
  SceneReferenceOptions fo;
  fo.progress = false;
  fo.on_step = [&](const SceneReferenceStep& s) { full.push_back(s.tool_forces->at(0).norm()); };
  run_scene_reference(sc, fo);
  std::vector<double> reduced;
  SceneSessionOptions so;
  so.progress = false;
  SceneSession session(sc, so);
  while (session.steps_done() < session.total_steps()) {
    session.advance();
    reduced.push_back(session.tool_state(0).force.norm());
  }
  Progress::set_quiet(false);
  ASSERT_EQ(r.pairs.size(), 1u);
  const SceneContactPair& p = r.pairs[0];
  EXPECT_EQ(p.object, "gripper");
  EXPECT_EQ(r.removed, "gripper");
  EXPECT_EQ(p.force_full_n, full);
  ASSERT_EQ(p.force_reduced_n.size(), reduced.size());
  for (size_t k = 0; k < reduced.size(); ++k) EXPECT_NEAR(p.force_reduced_n[k], reduced[k], 1e-9 * (1 + reduced[k])) << k;
  EXPECT_GT(p.peak_full_n, 0.2);
  EXPECT_GT(p.dent_full_max_mm, 1.0);  // the skin lifted under the tool
  EXPECT_EQ(p.force_full_n.back(), 0.0);  // released
}

// The same pinch with contact.patch: the anchors pull through a patch under
// the tool (contact_patch.hpp, PatchAnchors), whose tent the 6 handles
// cannot form alone; the force on the tool comes near the full FEM's.
TEST_F(SceneContactBench, WithThePatchAGraspingToolsForceComesNearTheFullFem) {
  std::string text = test::kBoxPinchScene;
  text.insert(text.find('\n') + 1, "contact: {patch: true, friction: 0}\n");
  Progress::set_quiet(true);
  const SceneContactBenchResult without = run_scene_contact_bench(read_scene_description(write_scene(test::kBoxPinchScene)), quiet());
  const SceneContactBenchResult with = run_scene_contact_bench(read_scene_description(write_scene(text)), quiet());
  Progress::set_quiet(false);
  ASSERT_EQ(with.pairs.size(), 1u);
  ASSERT_EQ(without.pairs.size(), 1u);
  const SceneContactPair &p = with.pairs[0], &q = without.pairs[0];
  std::cout << "[ pinch patch ] peak full " << p.peak_full_n << " N, with patch " << p.peak_reduced_n << " N (rms "
            << p.rms_err << ", " << p.max_patch_nodes << " nodes), without " << q.peak_reduced_n << " N (rms " << q.rms_err
            << ")\n";
  EXPECT_EQ(p.peak_full_n, q.peak_full_n);  // the reference does not see contact.patch
  EXPECT_GT(p.max_patch_nodes, 0);
  EXPECT_EQ(q.max_patch_nodes, 0);
  EXPECT_LT(p.rms_err, 0.25);
  EXPECT_LT(p.rms_err, 0.5 * q.rms_err);
}

TEST_F(SceneContactBench, FiguresAreThoseOfBothSolversRunsAndTheDepthIsTheBallsTravel) {
  const SceneDescription sc = read_scene_description(write_scene(ball_scene("kinematic", kLowered)));
  Progress::set_quiet(true);
  const SceneContactBenchResult r = run_scene_contact_bench(sc, quiet());
  // The same scene through `simulate --solver full` and `simulate`.
  SceneReferenceOptions fo;
  fo.progress = false;
  SceneContactStats full, reduced;
  run_scene_reference(sc, fo, &full);
  SceneRunOptions ro;
  ro.progress = false;
  run_scene(sc, ro, &reduced);
  Progress::set_quiet(false);

  ASSERT_EQ(r.time.size(), 30u);
  EXPECT_NEAR(r.time.back(), 0.3, 1e-12);
  EXPECT_EQ(r.body, "base");
  EXPECT_TRUE(r.patch);
  ASSERT_EQ(r.pairs.size(), 1u);
  const SceneContactPair& p = r.pairs[0];
  EXPECT_EQ(p.object, "ball");
  EXPECT_EQ(r.removed, "ball");
  for (const auto* series : {&p.force_full_n, &p.force_reduced_n, &p.dent_full_mm, &p.dent_reduced_mm, &p.depth_mm})
    EXPECT_EQ(series->size(), 30u);
  std::cout << "[ scene contact ] peak " << p.peak_full_n << " / " << p.peak_reduced_n << " N, rms " << p.rms_err
            << " over " << p.rms_steps << " steps, dent " << p.dent_full_max_mm << " / " << p.dent_reduced_max_mm
            << " mm, depth " << p.max_depth_mm << " mm, patch " << p.max_patch_nodes << ", ms " << r.ms_contact
            << " / " << r.ms_no_contact << " full " << r.ms_full << "\n";

  // Peaks: the runs' own contact figures.
  ASSERT_EQ(full.pairs.size(), 1u);
  EXPECT_NEAR(p.peak_full_n, full.pairs[0].max_force, 1e-9 * full.pairs[0].max_force);
  double reduced_peak = -1;
  for (const auto& q : reduced.pairs)
    if (q.term == "contact:ball") reduced_peak = q.max_force;
  EXPECT_NEAR(p.peak_reduced_n, reduced_peak, 1e-9 * reduced_peak);
  EXPECT_GT(p.peak_full_n, 0.05);
  // The errors from the series: the peak's, and the RMS over the steps above 5 % of the full peak.
  EXPECT_NEAR(p.peak_err, std::abs(p.peak_reduced_n - p.peak_full_n) / p.peak_full_n, 1e-12);
  double sum = 0;
  int n = 0;
  for (size_t k = 0; k < 30; ++k)
    if (p.force_full_n[k] > 0.05 * p.peak_full_n) {
      sum += std::pow(p.force_reduced_n[k] / p.force_full_n[k] - 1, 2);
      ++n;
    }
  EXPECT_EQ(p.rms_steps, n);
  EXPECT_GE(n, 10);  // in contact from ~0.1 s on
  EXPECT_NEAR(p.rms_err, std::sqrt(sum / n), 1e-12);
  // Six handles and the patch under the ball: the reduced force follows the full FEM's.
  EXPECT_LT(p.peak_err, 0.3);
  EXPECT_LT(p.rms_err, 0.5);

  // Depth: contact from ~0.1 s on (centre 1 cm above the top); 5 mm at the end, less
  // the ≤ 0.5 mm step before first contact and the face samples' offset from the axis.
  EXPECT_GT(p.max_depth_mm, 3.9);
  EXPECT_LE(p.max_depth_mm, 5.0 + 1e-9);
  EXPECT_NEAR(p.depth_mm.back(), p.max_depth_mm, 1e-9);  // held at the bottom
  EXPECT_LT(p.depth_mm.front(), -4.0);                   // 1.5 cm above at t = 0, ~1 cm before contact
  // The dent: the top gives millimetres under the 5 mm ball (simulate --solver full's test).
  EXPECT_GT(p.dent_full_max_mm, 2.0);
  EXPECT_LT(p.dent_full_max_mm, 6.0);
  EXPECT_GT(p.dent_reduced_max_mm, 0.5 * p.dent_full_max_mm);
  EXPECT_LT(p.dent_reduced_max_mm, 1.5 * p.dent_full_max_mm);
  EXPECT_EQ(p.dent_full_mm.front(), 0.0);  // nothing near the ball at the first step
  EXPECT_GT(p.max_patch_nodes, 0);
  EXPECT_GT(r.contact_steps, 10);
  EXPECT_LT(r.contact_steps, 30);
  EXPECT_GT(r.ms_contact, 0);
  EXPECT_GT(r.ms_no_contact, 0);
  EXPECT_NEAR(r.step_ratio, r.ms_contact / r.ms_no_contact, 1e-12);
  EXPECT_GT(r.ms_full, 0);

  // The reports: one CSV row per step, the table row of the ball.
  test::TempDir dir;
  write_scene_contact_series_csv(r, dir.file("s.csv"));
  write_scene_contact_plot_svg(r, dir.file("s.svg"));
  write_scene_contact_summary_csv({r}, dir.file("sum.csv"));
  std::ifstream csv(dir.file("s.csv"));
  int lines = 0;
  for (std::string line; std::getline(csv, line);) ++lines;
  EXPECT_EQ(lines, 31);
  EXPECT_TRUE(std::filesystem::exists(dir.file("s.svg")));
  std::ostringstream md;
  write_scene_contact_markdown({r}, quiet(), md);
  EXPECT_NE(md.str().find("| ball | 1/100 |"), std::string::npos) << md.str();
  EXPECT_NE(md.str().find("above 5 % of its peak"), std::string::npos) << md.str();
}

TEST_F(SceneContactBench, AStaticObjectHasNoDepthAndRefusedOrNonFiniteScenesFailNamingTheScene) {
  const SceneDescription pressed =
      read_scene_description(write_scene(ball_scene("static", "    position: [0.0, 0.037, 0.0]\n")));
  Progress::set_quiet(true);
  SceneDescription shorter = pressed;
  shorter.solver.seconds = 0.05;
  const SceneContactBenchResult r = run_scene_contact_bench(shorter, quiet());
  Progress::set_quiet(false);
  ASSERT_EQ(r.pairs.size(), 1u);
  EXPECT_TRUE(std::isnan(r.pairs[0].max_depth_mm));
  EXPECT_GT(r.pairs[0].peak_full_n, 0);
  EXPECT_EQ(r.contact_steps, 5);  // 3 mm into the top from the start

  const std::string head = "solver: {dt: 1/100, seconds: 0.1}\nbodies:\n  - {name: base, avatar: box.h5}\n";
  auto refused = [&](const std::string& text, std::initializer_list<std::string> fragments) {
    const SceneDescription sc = read_scene_description(write_scene(text));
    test::expect_error([&] { run_scene_contact_bench(sc, quiet()); }, fragments);
    test::expect_error([&] { check_scene_contact_bench(sc); }, fragments);
  };
  refused(head + "  - {name: other, avatar: box.h5, placement: {offset: [0.2, 0, 0]}}\n", {"scene.yaml", "one body"});
  refused(head + "objects:\n  - {name: rock, shape: {type: sphere, radius: 0.01}, kind: dynamic, density: 1000, "
                 "position: [0, 0.1, 0]}\n",
          {"scene.yaml", "objects 'rock'", "dynamic"});
  refused(head, {"scene.yaml", "touches no object", "no tool grasps"});
  // The full FEM never touches the ball: nothing to compare.
  const SceneDescription apart =
      read_scene_description(write_scene(ball_scene("static", "    position: [0.0, 0.1, 0.0]\n")));
  SceneDescription brief = apart;
  brief.solver.seconds = 0.02;
  Progress::set_quiet(true);
  test::expect_error([&] { run_scene_contact_bench(brief, quiet()); }, {"scene.yaml", "no contact", "ball"});
  // A non-finite value in the reduced run: stopped, naming the solver, the scene and the step.
  SceneContactBenchSettings nan = quiet();
  nan.inject_nan_at_step = 3;
  test::expect_error([&] { run_scene_contact_bench(shorter, nan); }, {"reduced solver", "scene.yaml", "step 3"});
  Progress::set_quiet(false);
}
