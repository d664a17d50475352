// The runtime's model/state split: block layout and groups, the
// assembler's scatter against an independent dense assembly, several bodies in
// one model, save/restore of a state, world frames through the pelvis-centred
// step, inactive terms and the report hook.
#include <gtest/gtest.h>

#include <cstdio>
#include <random>
#include <set>

#include "sflsh/core/rotation.hpp"
#include "sflsh/sim/energies/bone_residual.hpp"
#include "sflsh/sim/energies/elastic.hpp"
#include "sflsh/sim/simulator.hpp"
#include "sflsh/sim/state_file.hpp"
#include "sim/skeleton_fixture.hpp"
#include "sim/synthetic_avatar.hpp"
#include "test_support.hpp"

using namespace sflsh;

namespace {

/// A term with a random SPD quadratic over its local coordinates (bone
/// log-rotation and translation, then z, per bound body in local order):
/// E = ½ xᵀ A x + bᵀ x, gradient A x + b, Hessian A. Not a physical energy:
/// it exists to check where the assembler puts a term's local system.
class RandomQuadraticTerm : public EnergyTerm {
 public:
  RandomQuadraticTerm(BodyBlocks blocks, int local_size, unsigned seed) : blocks_(blocks) {
    std::mt19937 rng(seed);
    std::normal_distribution<double> n(0.0, 1.0);
    MatX M(local_size, local_size);
    for (int i = 0; i < local_size; ++i)
      for (int j = 0; j < local_size; ++j) M(i, j) = n(rng);
    A_ = M * M.transpose() + MatX::Identity(local_size, local_size);
    b_.resize(local_size);
    for (int i = 0; i < local_size; ++i) b_[i] = n(rng);
  }
  std::string name() const override { return "random_quadratic"; }
  BodyBlocks blocks() const override { return blocks_; }
  /// Local coordinates of the bound bodies (see class comment).
  static VecX coordinates(const StepContext& ctx, int local_size) {
    VecX x = VecX::Zero(local_size);
    for (const BoundBody& b : ctx.bound) {
      const DofLayout& l = b.layout;
      if (l.bones_dynamic)
        for (int i = 0; i < l.num_bones; ++i) {
          x.segment<3>(l.bone_offset(i)) = rotation_log(b.q->bones[i].linear());
          x.segment<3>(l.bone_offset(i) + 3) = b.q->bones[i].translation();
        }
      if (l.num_reduced > 0) x.segment(l.z_offset(), l.num_reduced) = b.q->z;
    }
    return x;
  }
  double compute(const StepContext& ctx, const Configuration&, VecRef* grad, MatRef* hess) const override {
    const VecX x = coordinates(ctx, int(b_.size()));
    if (grad) *grad += A_ * x + b_;
    if (hess) *hess += A_;
    return 0.5 * x.dot(A_ * x) + b_.dot(x);
  }
  const MatX& A() const { return A_; }
  const VecX& b() const { return b_; }

 private:
  BodyBlocks blocks_;
  MatX A_;
  VecX b_;
};

/// ½ k |p − f|², p = the pelvis of the bound body, f = its input frame's
/// origin: pulls the body towards a world-fixed anchor. Inactive when the
/// frame is not among the step's inputs; reports the spring force on the body.
class AnchorSpringTerm : public EnergyTerm {
 public:
  AnchorSpringTerm(std::string frame, double k) : frame_(std::move(frame)), k_(k) {}
  std::string name() const override { return "anchor_spring"; }
  BodyBlocks blocks() const override { return BodyBlocks::Bones; }
  std::vector<std::string> input_frames() const override { return {frame_}; }
  bool active(const StepContext& ctx) const override { return ctx.frame() != nullptr; }
  double compute(const StepContext& ctx, const Configuration& q, VecRef* grad, MatRef* hess) const override {
    const Vec3 p = q.bones[0] * Vec3(ctx.avatar->joints_rest.row(0).transpose());
    const Vec3 r = p - ctx.frame()->pose.translation();
    const Mat36 J = point_jacobian(p);
    if (grad) grad->segment<6>(ctx.layout.bone_offset(0)) += k_ * J.transpose() * r;
    if (hess) hess->block<6, 6>(ctx.layout.bone_offset(0), ctx.layout.bone_offset(0)) += k_ * J.transpose() * J;
    return 0.5 * k_ * r.squaredNorm();
  }
  std::vector<TermQuantity> report(const StepContext& ctx, const Configuration& q) const override {
    const Vec3 p = q.bones[0] * Vec3(ctx.avatar->joints_rest.row(0).transpose());
    const Vec3 f = -k_ * (p - ctx.frame()->pose.translation());
    return {{"force", "N", f}};
  }

 private:
  std::string frame_;
  double k_;
};

std::shared_ptr<const Avatar> box_avatar(int handles, double x_offset = 0.0) {
  test::SyntheticAvatarOptions so;
  so.handles = handles;
  so.all_tets = false;
  so.samples = 10;
  Avatar a = test::make_synthetic_avatar(so);
  a.joints_rest = test::make_tpose_skeleton().joints_rest;
  for (Eigen::Index i = 0; i < a.tet.nodes.rows(); ++i) a.tet.nodes(i, 0) += x_offset;
  return std::make_shared<const Avatar>(std::move(a));
}

std::vector<Isometry> shifted(const std::vector<Isometry>& bones, const Vec3& d) {
  std::vector<Isometry> out = bones;
  for (Isometry& G : out) G.translation() += d;
  return out;
}

/// Global DoF indices of a bound body's touched blocks, from Model::blocks()
/// alone (independent of the model's own placements).
std::vector<int> global_indices(const Model& m, int body, BodyBlocks use) {
  std::vector<int> idx;
  for (const DofBlock& blk : m.blocks()) {
    if (blk.body != body) continue;
    const bool take = (blk.kind == DofBlock::Kind::Bone && use != BodyBlocks::Soft) ||
                      (blk.kind == DofBlock::Kind::Soft && use != BodyBlocks::Bones);
    if (take)
      for (int k = 0; k < blk.size; ++k) idx.push_back(blk.offset + k);
  }
  return idx;
}

}  // namespace

TEST(Model, BlocksFollowBodiesAndGroupsAreIntervals) {
  ModelBuilder b;
  const int a0 = b.add_body({"a", box_avatar(3), true});
  const int a1 = b.add_body({"b", box_avatar(2), false});
  const int a2 = b.add_body({"c", box_avatar(4), true});
  // Couple a and c: they form one group, b is alone.
  b.add_term(std::make_shared<RandomQuadraticTerm>(BodyBlocks::Soft, 9 + 12, 1), {a0, a2});
  const auto m = b.build();
  ASSERT_EQ(m->groups().size(), 2u);
  EXPECT_EQ(m->groups()[0].bodies, (std::vector<int>{a0, a2}));
  EXPECT_EQ(m->groups()[1].bodies, (std::vector<int>{a1}));
  // 6·24 + 9, then 6·24 + 12, then (kinematic) 6.
  EXPECT_EQ(m->bodies()[a0].layout.base, 0);
  EXPECT_EQ(m->bodies()[a2].layout.base, 153);
  EXPECT_EQ(m->bodies()[a1].layout.base, 153 + 156);
  EXPECT_EQ(m->num_dofs(), 153 + 156 + 6);
  EXPECT_EQ(m->blocks().size(), size_t(24 + 1 + 24 + 1 + 1));
  // The coupling term's soft blocks are not adjacent: it is scattered.
  const TermPlacement& p = m->terms()[0].placement;
  EXPECT_FALSE(p.contiguous);
  EXPECT_EQ(p.ranges, (std::vector<std::pair<int, int>>{{144, 9}, {153 + 144, 12}}));
  EXPECT_EQ(m->body_index("c"), a2);
  test::expect_error([&] { m->body_index("nobody"); }, {"unknown body 'nobody'"});
}

TEST(Model, BuilderRejectsBadBindings) {
  ModelBuilder b;
  b.add_body({"a", box_avatar(2), true});
  test::expect_error([&] { b.add_body({"a", box_avatar(2), true}); }, {"two bodies are called 'a'"});
  test::expect_error([&] { b.add_term(std::make_shared<RandomQuadraticTerm>(BodyBlocks::Soft, 6, 1), {0, 3}); },
                     {"names body 3"});
  test::expect_error([&] { b.add_term(std::make_shared<RandomQuadraticTerm>(BodyBlocks::Soft, 6, 1), {0, 0}); },
                     {"names body 0 twice"});
  b.options().h = 0;
  test::expect_error([&] { b.build(); }, {"time step h = 0"});
}

TEST(Model, ScatterMatchesADenseReferenceOnRandomLayouts) {
  for (unsigned seed = 1; seed <= 8; ++seed) {
    std::mt19937 rng(seed);
    ModelBuilder b;
    const int B = 2 + int(rng() % 3);
    for (int i = 0; i < B; ++i)
      b.add_body({"body" + std::to_string(i), box_avatar(1 + int(rng() % 3)), bool(rng() % 2)});
    const auto build_probe = b.build();  // layouts, to size the random terms
    std::vector<std::shared_ptr<const RandomQuadraticTerm>> terms;
    std::vector<std::vector<int>> bound;
    const int T = 3 + int(rng() % 4);
    for (int t = 0; t < T; ++t) {
      std::vector<int> bodies;
      const int nb = 1 + int(rng() % 2);
      while (int(bodies.size()) < nb) {
        const int c = int(rng() % B);
        if (std::find(bodies.begin(), bodies.end(), c) == bodies.end()) bodies.push_back(c);
      }
      const BodyBlocks use = BodyBlocks(rng() % 3);
      int local = 0;
      for (int c : bodies) local += int(global_indices(*build_probe, c, use).size());
      if (local == 0) continue;
      auto term = std::make_shared<const RandomQuadraticTerm>(use, local, seed * 100 + t);
      b.add_term(term, bodies);
      terms.push_back(term);
      bound.push_back(bodies);
    }
    const auto m = b.build();

    // Random configurations.
    std::vector<Configuration> q(B);
    for (int i = 0; i < B; ++i) {
      q[i] = test::random_bones(rng, 0.8, 0.3);
      q[i].z = VecX::Random(m->bodies()[i].avatar->num_reduced());
    }

    // Dense reference: each term's local system mapped by indices derived from blocks().
    const int n = m->num_dofs();
    VecX g_ref = VecX::Zero(n);
    MatX H_ref = MatX::Zero(n, n);
    double E_ref = 0;
    for (size_t t = 0; t < terms.size(); ++t) {
      std::vector<int> idx;
      for (int c : bound[t]) {
        const std::vector<int> gi = global_indices(*m, c, terms[t]->blocks());
        idx.insert(idx.end(), gi.begin(), gi.end());
      }
      StepContext ctx;
      for (size_t k = 0; k < bound[t].size(); ++k)
        ctx.bound.push_back({bound[t][k], 0, nullptr, m->terms()[t].local_layouts[k], &q[bound[t][k]]});
      const VecX x = RandomQuadraticTerm::coordinates(ctx, int(idx.size()));
      E_ref += 0.5 * x.dot(terms[t]->A() * x) + terms[t]->b().dot(x);
      const VecX gl = terms[t]->A() * x + terms[t]->b();
      for (size_t i = 0; i < idx.size(); ++i) {
        g_ref[idx[i]] += gl[i];
        for (size_t j = 0; j < idx.size(); ++j) H_ref(idx[i], idx[j]) += terms[t]->A()(i, j);
      }
    }

    // The assembler, group by group, with the model's placements.
    VecX g = VecX::Zero(n);
    MatX H = MatX::Zero(n, n);
    double E = 0;
    for (const Model::Group& grp : m->groups()) {
      StepSystem sys;
      sys.size = grp.size;
      sys.bodies = grp.layouts;
      std::vector<StepContext> contexts(grp.terms.size());
      std::vector<Configuration> qg;
      for (int c : grp.bodies) qg.push_back(q[c]);
      for (size_t k = 0; k < grp.terms.size(); ++k) {
        const Model::BoundTerm& bt = m->terms()[grp.terms[k]];
        for (size_t j = 0; j < bt.bodies.size(); ++j)
          contexts[k].bound.push_back({bt.bodies[j], grp.slots[k][j], nullptr, bt.local_layouts[j]});
        sys.terms.push_back({bt.term.get(), &contexts[k], grp.placements[k], true});
      }
      VecX gg;
      MatX Hg;
      E += total_energy(sys, qg, &gg, &Hg);
      g.segment(grp.offset, grp.size) = gg;
      H.block(grp.offset, grp.offset, grp.size, grp.size) = Hg;
    }
    EXPECT_NEAR(E, E_ref, 1e-9 * std::abs(E_ref)) << "seed " << seed;
    EXPECT_LT((g - g_ref).norm(), 1e-12 * g_ref.norm()) << "seed " << seed << "\n" << m->describe();
    EXPECT_LT((H - H_ref).norm(), 1e-12 * H_ref.norm()) << "seed " << seed << "\n" << m->describe();
  }
}

namespace {

SkeletonTermsOptions skeleton_options() {
  SkeletonTermsOptions o;
  o.body_mass = 70.0;
  return o;
}

/// A 1 Hz sway and bob of the synthetic skeleton, placed at `offset`.
std::vector<Isometry> sway(const Avatar& a, double t, const Vec3& offset, double phase) {
  return shifted(test::synthetic_motion(a, t + phase, 0.03, 0.4), offset);
}

}  // namespace

TEST(Model, TwoAvatarsThatDoNotInteractGetExactlyTheirSingleAvatarResults) {
  const auto a = box_avatar(4), b = box_avatar(6);
  SimulatorOptions so;
  so.bones_dynamic = true;
  so.damping = 0.005;
  // Any departure from the quadratic model adds an iteration: the groups' reports must merge them.
  so.newton.nonlinearity_tolerance = 1e-9;
  const SkeletonTermsOptions sk = skeleton_options();
  const Vec3 off_a(0.3, 0, -0.2), off_b(2.5, 0.1, 4.0);

  // Each alone.
  Simulator alone_a(avatar_model(a, so, &sk)), alone_b(avatar_model(b, so, &sk));
  alone_a.reset(sway(*a, 0, off_a, 0.0));
  alone_b.reset(sway(*b, 0, off_b, 0.3));
  // Both in one model.
  ModelBuilder mb(model_options(so));
  const int ia = mb.add_body({"a", a, true}), ib = mb.add_body({"b", b, true});
  add_soft_tissue_terms(mb, ia, {true, so.damping});
  add_skeleton_terms(mb, ia, sk);
  add_soft_tissue_terms(mb, ib, {true, so.damping});
  add_skeleton_terms(mb, ib, sk);
  Simulator both(mb.build());
  ASSERT_EQ(both.model().groups().size(), 2u);
  State s = both.scene_state();
  s.bodies[ia] = alone_a.scene_state().bodies[0];
  s.bodies[ib] = alone_b.scene_state().bodies[0];
  both.set_state(s);

  int added = 0;
  for (int i = 1; i <= 40; ++i) {
    const double t = i * so.h;
    const auto ta = sway(*a, t, off_a, 0.0), tb = sway(*b, t, off_b, 0.3);
    const StepReport ra = alone_a.step(ta), rb = alone_b.step(tb);
    StepInputs in;
    in.bodies = {{ta, {}}, {tb, {}}};
    const StepReport rep = both.step(in);
    ASSERT_EQ(rep.energies.size(), both.model().terms().size());
    EXPECT_EQ(rep.iterations_for_nonlinearity, std::max(ra.iterations_for_nonlinearity, rb.iterations_for_nonlinearity));
    EXPECT_EQ(rep.iterations_after_damping, std::max(ra.iterations_after_damping, rb.iterations_after_damping));
    added += rep.iterations_for_nonlinearity;
  }
  EXPECT_GT(added, 0);
  for (int body : {ia, ib}) {
    const Simulator& alone = body == ia ? alone_a : alone_b;
    EXPECT_EQ(both.state(body).z, alone.state().z) << "body " << body;
    for (int j = 0; j < 24; ++j)
      EXPECT_EQ(both.state(body).bones[j].matrix(), alone.state().bones[j].matrix()) << "body " << body << " bone " << j;
  }
  EXPECT_GT(both.state(ib).z.norm(), 1e-5);  // the soft tissue did move
}

TEST(Model, ParallelAndSerialGroupsGiveIdenticalResults) {
  const auto a = box_avatar(4);
  SimulatorOptions so;
  so.bones_dynamic = true;
  const SkeletonTermsOptions sk = skeleton_options();
  std::vector<Configuration> finals[2];
  for (bool parallel : {false, true}) {
    ModelBuilder mb(model_options(so));
    mb.options().parallel_groups = parallel;
    for (int i = 0; i < 4; ++i) {
      const int body = mb.add_body({"a" + std::to_string(i), a, true});
      add_soft_tissue_terms(mb, body);
      add_skeleton_terms(mb, body, sk);
    }
    Simulator sim(mb.build());
    for (int s = 1; s <= 10; ++s) {
      StepInputs in;
      for (int i = 0; i < 4; ++i) in.bodies.push_back({sway(*a, s * so.h, Vec3(i, 0, 0), 0.1 * i), {}});
      sim.step(in);
    }
    for (int i = 0; i < 4; ++i) finals[parallel].push_back(sim.state(i));
  }
  for (int i = 0; i < 4; ++i) EXPECT_EQ(finals[0][i].z, finals[1][i].z);
}

TEST(Model, ResumedRunEqualsTheUninterruptedOne) {
  const auto a = box_avatar(5);
  SimulatorOptions so;
  so.bones_dynamic = true;
  const SkeletonTermsOptions sk = skeleton_options();
  const auto model = avatar_model(a, so, &sk);
  const Vec3 off(0.5, 0, 0.5);
  auto run = [&](Simulator& sim, int from, int to) {
    for (int i = from + 1; i <= to; ++i) sim.step(sway(*a, i * so.h, off, 0.0));
  };
  Simulator whole(model);
  whole.reset(sway(*a, 0, off, 0.0));
  run(whole, 0, 30);

  Simulator first(model);
  first.reset(sway(*a, 0, off, 0.0));
  run(first, 0, 13);
  const std::string path = testing::TempDir() + "/sflsh_state_test.h5";
  write_state(path, first.model(), first.scene_state());
  Simulator resumed(model);
  resumed.set_state(read_state(path, resumed.model()));
  EXPECT_EQ(resumed.time(), first.time());
  run(resumed, 13, 30);
  EXPECT_EQ(resumed.state().z, whole.state().z);
  EXPECT_EQ(resumed.previous_state().z, whole.previous_state().z);
  for (int j = 0; j < 24; ++j) EXPECT_EQ(resumed.state().bones[j].matrix(), whole.state().bones[j].matrix());
  EXPECT_EQ(resumed.time(), whole.time());

  // An in-memory copy resumes the same way.
  State copy = first.scene_state();
  Simulator again(model);
  again.set_state(copy);
  run(again, 13, 30);
  EXPECT_EQ(again.state().z, whole.state().z);

  // A state file for another scene is refused, naming the file and the body.
  ModelBuilder other;
  other.add_body({"someone", a, true});
  test::expect_error([&] { read_state(path, *other.build()); }, {"'avatar'"});
  std::remove(path.c_str());
  test::expect_error([&] { read_state(path, *model); }, {path});
}

TEST(Model, AWorldFixedAnchorStaysWhereTheSceneHasIt) {
  // The step is centred on the pelvis; a world frame given as an input must
  // be shifted with everything else, so the body settles at the anchor's
  // world position, far from both the origin and its start.
  const auto a = box_avatar(3);
  ModelBuilder mb;
  mb.options().gravity = Vec3::Zero();
  const int body = mb.add_body({"avatar", a, true});
  add_soft_tissue_terms(mb, body);
  SkeletonTermsOptions sk = skeleton_options();
  sk.tracking = false;
  add_skeleton_terms(mb, body, sk);
  mb.add_term(std::make_unique<AnchorSpringTerm>("anchor", 2000.0), body);
  Simulator sim(mb.build());
  sim.reset(test::synthetic_motion(*a, 0.0, 0.0, 0.0));
  const Vec3 anchor(3.0, 1.5, -2.0);
  StepInputs in;
  in.bodies = {{sim.state().bones, {}}};
  const FrameId anchor_frame = sim.model().frame_id("anchor");
  in.frames[anchor_frame].pose.translation() = anchor;
  StepReport rep;
  // Nothing damps the swing but backward Euler itself (the flesh rings for a
  // few seconds after the 4 m pull, 7.1 kN at the first step). What is left
  // after 20 s swings slowly about rest, its phase in the last bits: 0.66 N
  // at the last step with one build, 1.11 N with another (a unity build).
  double first_force = 0;
  for (int i = 0; i < 1200; ++i) {
    rep = sim.step(in);
    if (i == 0 && rep.quantities.size() == 1) first_force = Eigen::Map<const Vec3>(rep.quantities[0].value.data()).norm();
  }
  EXPECT_LT((sim.joints().row(0).transpose() - anchor).norm(), 1e-3);
  EXPECT_EQ(in.frames.find(anchor_frame)->pose.translation(), anchor);
  // The report hook: the spring's force on the body, ~0 at rest (below 1e-3
  // of the first step's pull).
  ASSERT_EQ(rep.quantities.size(), 1u);
  EXPECT_EQ(rep.quantities[0].term, "anchor_spring");
  EXPECT_EQ(rep.quantities[0].unit, "N");
  EXPECT_GT(first_force, 1e3);
  EXPECT_LT(Eigen::Map<const Vec3>(rep.quantities[0].value.data()).norm(), 1e-3 * first_force);

  // Without the frame the term sits the step out: energy 0, no time, no report.
  StepInputs none;
  none.bodies = in.bodies;
  rep = sim.step(none);
  const TermEnergy& spring = rep.energies.back();
  EXPECT_EQ(spring.name, "anchor_spring");
  EXPECT_FALSE(spring.active);
  EXPECT_EQ(spring.value, 0.0);
  EXPECT_EQ(spring.ms, 0.0);
  EXPECT_TRUE(rep.quantities.empty());
}

TEST(Model, ASceneWithoutSoftTissueTermsBuildsNoElasticTerm) {
  SimulatorOptions so;
  so.bones_dynamic = true;
  so.soft_tissue_terms = false;
  const SkeletonTermsOptions sk = skeleton_options();
  const auto m = avatar_model(box_avatar(3), so, &sk);
  EXPECT_EQ(m->find_term<ElasticTerm>(0), nullptr);
  for (const Model::BoundTerm& t : m->terms()) EXPECT_EQ(t.term->blocks(), BodyBlocks::Bones) << t.term->name();
}
