// Step inputs by id: the ModelBuilder hands out one FrameId per world frame
// and one AnchorSetId per anchor term, StepInputs holds the inputs in vectors
// indexed by them, and every term reads the inputs bound to it, not its
// neighbours' — whatever order the ids were handed out in.
#include <gtest/gtest.h>

#include <memory>
#include <tuple>

#include "sflsh/core/error.hpp"
#include "sflsh/sim/energies/anchor.hpp"
#include "sflsh/sim/simulator.hpp"
#include "sflsh/sim/soft_tissue_terms.hpp"
#include "sim/skeleton_fixture.hpp"
#include "sim/synthetic_avatar.hpp"
#include "test_support.hpp"

using namespace sflsh;

namespace {

/// Reports where its input frame is (world, "seen", m), or nothing when the
/// frame is not given; adds no energy.
class FrameProbeTerm : public EnergyTerm {
 public:
  explicit FrameProbeTerm(std::string frame) : frame_(std::move(frame)) {}
  std::string name() const override { return "probe:" + frame_; }
  std::vector<std::string> input_frames() const override { return {frame_}; }
  double compute(const StepContext&, const Configuration&, VecRef*, MatRef*) const override { return 0; }
  std::vector<TermQuantity> report(const StepContext& ctx, const Configuration&) const override {
    if (!ctx.frame()) return {};
    return {{"seen", "m", ctx.frame()->pose.translation() + ctx.frame_origin}};
  }

 private:
  std::string frame_;
};

std::shared_ptr<const Avatar> box() { return test::make_tpose_box(4, 10); }

const TermQuantityReport* find(const StepReport& r, const std::string& term, const std::string& name) {
  for (const TermQuantityReport& q : r.quantities)
    if (q.term == term && q.name == name) return &q;
  return nullptr;
}

Vec3 vec3(const TermQuantityReport& q) { return Vec3(q.value.at(0), q.value.at(1), q.value.at(2)); }

}  // namespace

TEST(StepInputs, EachTermReadsTheFrameAndAnchorSetBoundToIt) {
  const auto a = box();
  ModelBuilder mb;
  mb.options().gravity = Vec3::Zero();
  const int body = mb.add_body({"avatar", a, false});
  add_soft_tissue_terms(mb, body);
  // Ids handed out in another order than the terms': "right" and tool_b's set first.
  const FrameId right = mb.add_frame("right");
  const AnchorSetId set_b = mb.add_anchor_set("tool_b");
  mb.add_term(std::make_unique<FrameProbeTerm>("left"), body);
  mb.add_term(std::make_unique<FrameProbeTerm>("right"), body);
  // Soft springs (1 mN/m): the flesh barely moves, the force is k (a − x_rest).
  const double k = 1e-3;
  const PosedPoints skin = PosedPoints::at_surface(*a);
  mb.add_term(std::make_unique<AnchorTerm>("tool_a", skin, false, AnchorOptions{k, 0.0}), body);
  mb.add_term(std::make_unique<AnchorTerm>("tool_b", skin, false, AnchorOptions{k, 0.0}), body);
  EXPECT_EQ(mb.add_frame("right"), right);  // registered once
  Simulator sim(mb.build());
  const Model& m = sim.model();
  ASSERT_EQ(m.frame_names().size(), 2u);
  const FrameId left = m.frame_id("left");
  EXPECT_EQ(m.frame_id("right"), right);
  EXPECT_NE(left, right);
  const AnchorSetId set_a = m.anchor_set_id("tool_a");
  EXPECT_EQ(m.anchor_set_id("tool_b"), set_b);
  EXPECT_NE(set_a, set_b);
  test::expect_error([&] { m.frame_id("middle"); }, {"middle", "left", "right"});

  StepInputs in;
  in.bodies.push_back({identity_bones(), {}});
  in.frames[left].pose.translation() = Vec3(-0.3, 0.1, 0.02);
  in.frames[right].pose.translation() = Vec3(0.4, -0.2, 0.05);
  const Configuration rest = sim.state();
  const Vec3 x3 = skin.world_point(3, rest), x7 = skin.world_point(7, rest);
  const Vec3 a3 = x3 + Vec3(0.1, 0, 0), a7 = x7 + Vec3(0, 0, -0.2);
  in.anchors.resize(2);
  in.anchors[size_t(set_a.index)] = {AnchorPoint{3, a3, Vec3::Zero()}};
  in.anchors[size_t(set_b.index)] = {AnchorPoint{7, a7, Vec3::Zero()}};
  const StepReport rep = sim.step(in);

  const TermQuantityReport *seen_left = find(rep, "probe:left", "seen"), *seen_right = find(rep, "probe:right", "seen");
  ASSERT_TRUE(seen_left && seen_right);
  EXPECT_LT((vec3(*seen_left) - Vec3(-0.3, 0.1, 0.02)).norm(), 1e-12);
  EXPECT_LT((vec3(*seen_right) - Vec3(0.4, -0.2, 0.05)).norm(), 1e-12);
  const std::vector<std::tuple<std::string, int, Vec3>> expected = {{"tool_a", 3, a3 - x3}, {"tool_b", 7, a7 - x7}};
  for (const auto& [tool, point, pull] : expected) {
    const std::string term = "anchor:" + tool;
    const TermQuantityReport *points = find(rep, term, "anchor_points"), *force = find(rep, term, "force");
    ASSERT_TRUE(points && force) << tool;
    ASSERT_EQ(points->value.size(), 1u) << tool;
    EXPECT_EQ(points->value[0], point) << tool;
    EXPECT_LT((vec3(*force) - k * pull).norm(), 1e-3 * k * pull.norm()) << tool << ": " << vec3(*force).transpose();
  }

  // A frame given by name reaches the same term; a frame not given is seen by no one.
  StepInputs by_name;
  by_name.bodies = in.bodies;
  by_name.frames["left"].pose.translation() = Vec3(0.7, 0, 0);
  const StepReport rep2 = sim.step(by_name);
  ASSERT_TRUE(find(rep2, "probe:left", "seen"));
  EXPECT_EQ(vec3(*find(rep2, "probe:left", "seen")), Vec3(0.7, 0, 0));
  EXPECT_EQ(find(rep2, "probe:right", "seen"), nullptr);
  EXPECT_EQ(find(rep2, "anchor:tool_a", "force"), nullptr);  // no anchors given: inactive
}

TEST(StepInputs, AQuantityNamesTheModelTermThatReportedIt) {
  const auto a = box();
  ModelBuilder mb;
  const int body = mb.add_body({"avatar", a, false});
  add_soft_tissue_terms(mb, body);
  const int left = mb.add_term(std::make_unique<FrameProbeTerm>("left"), body);
  const int right = mb.add_term(std::make_unique<FrameProbeTerm>("right"), body);
  Simulator sim(mb.build());
  ASSERT_EQ(sim.model().terms()[size_t(left)].term->name(), "probe:left");
  StepInputs in;
  in.bodies.push_back({identity_bones(), {}});
  in.frames[sim.model().frame_id("left")] = WorldFrame{};
  in.frames[sim.model().frame_id("right")] = WorldFrame{};
  const StepReport rep = sim.step(in);
  int seen = 0;
  for (const TermQuantityReport& q : rep.quantities) {
    if (q.name != "seen") continue;
    ++seen;
    EXPECT_EQ(q.term_index, q.term == "probe:left" ? left : right);
    EXPECT_EQ(sim.model().terms()[size_t(q.term_index)].term->name(), q.term);
  }
  EXPECT_EQ(seen, 2);
}
