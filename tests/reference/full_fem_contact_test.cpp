// Rigid obstacles and anchors in the full-FEM reference (samples on the skin's faces,
// pressure stiffness κ): the contact energy, gradient and Gauss–Newton Hessian
// against an independent closed-form sphere penalty over the face samples and
// finite differences (skin vertices embedded with mixed barycentric
// coordinates, bones posed); a free box resting on a floor, whose contact force
// must equal its weight over the bottom's area; and the reduced model with a
// complete basis (W = I) against the reference under a sphere pressed into the
// box while it moves (disabled: the reduced SdfContactTerm still samples skin
// vertices, so the two contact discretizations differ).
#include <gtest/gtest.h>

#include <map>
#include <random>
#include <set>

#include "sflsh/core/error.hpp"
#include "sflsh/geometry/primitive_sdfs.hpp"
#include "sflsh/sim/energies/contact_patch.hpp"
#include "sflsh/sim/energies/sdf_contact.hpp"
#include "sflsh/reference/full_fem.hpp"
#include "sflsh/sim/simulator.hpp"
#include "sflsh/sim/soft_tissue_terms.hpp"
#include "sim/synthetic_avatar.hpp"

namespace sflsh {
namespace {

/// Moves every skin vertex inside its tet (barycentric 0.7 at its own node,
/// 0.1 at the others), so a sample's position mixes four nodes.
Avatar with_embedded_skin(Avatar a) {
  for (Eigen::Index v = 0; v < a.surface_rest.rows(); ++v) {
    Vec3 x = Vec3::Zero();
    for (int c = 0; c < 4; ++c) {
      a.surface_bary(v, c) = a.surface_bary(v, c) > 0.5 ? 0.7 : 0.1;
      x += a.surface_bary(v, c) * a.tet.nodes.row(a.tet.elements(a.surface_tet[v], c)).transpose();
    }
    a.surface_rest.row(v) = x.transpose();
  }
  return a;
}

/// Skin vertex v in the world for nodal u and bones, straight from the asset.
Vec3 skin_world(const Avatar& a, int v, const Points& u, const std::vector<Isometry>& bones) {
  Vec3 y = a.surface_rest.row(v).transpose();
  for (int c = 0; c < 4; ++c) y += a.surface_bary(v, c) * u.row(a.tet.elements(a.surface_tet[v], c)).transpose();
  Vec3 x = Vec3::Zero();
  for (int j = 0; j < 24; ++j) x += a.surface_weights(v, j) * (bones[j] * y);
  return x;
}

TEST(FullFemContact, SphereEnergyGradientAndGaussNewtonHessian) {
  test::SyntheticAvatarOptions so;
  so.handles = 0;
  const auto a = std::make_shared<const Avatar>(with_embedded_skin(test::make_synthetic_avatar(so)));
  FullFemOptions o;
  o.gravity = Vec3::Zero();
  FullFem with(a, o), without(a, o);
  const double r = 0.08, kappa = 2.0e8, spacing = 0.015;  // a few samples per 4 cm face
  with.add_obstacle({"ball", std::make_shared<geometry::SphereSdf>(r), kappa, spacing});
  const auto bones = test::synthetic_motion(*a, 0.1, 0.03, 0.1);
  // The ball 2.5 cm into the highest skin point of the posed box.
  Vec3 top = Vec3(0, -1, 0);
  for (int v = 0; v < a->surface_rest.rows(); ++v) {
    const Vec3 x = skin_world(*a, v, Points::Zero(a->tet.num_nodes(), 3), bones);
    if (x.y() > top.y()) top = x;
  }
  const Vec3 c = top + Vec3(0.004, r - 0.025, -0.003);
  Isometry pose = Isometry::Identity();
  pose.translation() = c;
  with.step(bones, {pose});
  without.step(bones);

  // A state near rest (where the ball penetrates), perturbed: the step's
  // bones and prediction make the energy's context.
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> U(-1e-3, 1e-3);
  Points u = Points::Zero(a->tet.num_nodes(), 3);
  for (int n = 0; n < u.rows(); ++n)
    if (a->node_role[n] == int(NodeRole::Simulated))
      for (int i = 0; i < 3; ++i) u(n, i) += U(rng);
  std::vector<int> free_of(a->tet.num_nodes(), -1);
  int nfree = 0;
  for (int n = 0; n < a->tet.num_nodes(); ++n)
    if (a->node_role[n] == int(NodeRole::Simulated)) free_of[n] = nfree++;

  // Independent closed form: E = Σ_s ½ κ a_s min(|x_s − c| − r, 0)², x_s = Σ_i λ_i x_{v_i}.
  std::vector<SkinFaceSample> samples;
  for (int f = 0; f < a->surface_faces.rows(); ++f)
    append_face_samples(a->surface_rest, a->surface_faces, f, spacing, samples);
  auto sample_world = [&](const SkinFaceSample& s, const Points& uu) {
    Vec3 x = Vec3::Zero();
    for (int i = 0; i < 3; ++i) x += s.lambda[i] * skin_world(*a, a->surface_faces(s.face, i), uu, bones);
    return x;
  };
  auto contact = [&](const Points& uu) {
    double E = 0;
    for (const SkinFaceSample& s : samples) {
      const double d = (sample_world(s, uu) - c).norm() - r;
      if (d < 0) E += 0.5 * kappa * s.area * d * d;
    }
    return E;
  };
  const Points skin = with.skin_points(u);
  for (int v = 0; v < a->surface_rest.rows(); ++v)
    EXPECT_LT((skin.row(v).transpose() - skin_world(*a, v, u, bones)).norm(), 1e-14);
  VecX g1, g0;
  Eigen::SparseMatrix<double> H1, H0;
  const double E = with.energy(u, &g1, &H1) - without.energy(u, &g0, &H0);
  const double Ec = contact(u);
  ASSERT_GT(Ec, 0);
  EXPECT_NEAR(E, Ec, 1e-9 * Ec);
  const VecX g = g1 - g0;
  VecX fd(3 * nfree);
  MatX Hfd = MatX::Zero(3 * nfree, 3 * nfree);
  const double eps = 1e-7;
  for (int n = 0; n < u.rows(); ++n)
    for (int i = 0; i < 3 && free_of[n] >= 0; ++i) {
      Points up = u, um = u;
      up(n, i) += eps;
      um(n, i) -= eps;
      fd[3 * free_of[n] + i] = (contact(up) - contact(um)) / (2 * eps);
    }
  EXPECT_LT((g - fd).norm(), 1e-6 * fd.norm());
  // Gauss–Newton: κ Σ_s a_s j_s j_sᵀ over penetrating samples, j_s = ∂φ_s/∂u by finite differences.
  int active = 0;
  std::set<int> faces_of_tets_apart;  // active faces whose vertices sit in different tets
  for (const SkinFaceSample& s : samples) {
    auto phi = [&](const Points& uu) { return (sample_world(s, uu) - c).norm() - r; };
    if (phi(u) >= 0) continue;
    ++active;
    VecX j = VecX::Zero(3 * nfree);
    for (int vi = 0; vi < 3; ++vi) {
      const int v = a->surface_faces(s.face, vi);
      if (a->surface_tet[v] != a->surface_tet[a->surface_faces(s.face, 0)]) faces_of_tets_apart.insert(s.face);
      for (int cc = 0; cc < 4; ++cc) {
        const int n = a->tet.elements(a->surface_tet[v], cc);
        for (int i = 0; i < 3 && free_of[n] >= 0; ++i) {
          Points up = u, um = u;
          up(n, i) += eps;
          um(n, i) -= eps;
          j[3 * free_of[n] + i] = (phi(up) - phi(um)) / (2 * eps);
        }
      }
    }
    Hfd += kappa * s.area * j * j.transpose();
  }
  EXPECT_GT(active, 10);
  EXPECT_GT(faces_of_tets_apart.size(), 0u);  // the Hessian couples nodes of different tets
  const MatX H = MatX(H1) - MatX(H0);
  EXPECT_LT((H - Hfd).norm(), 1e-6 * Hfd.norm());
  // Some sample couples nodes of its face's tets: the off-diagonal node blocks are filled.
  EXPECT_GT((Hfd - MatX(Hfd.diagonal().asDiagonal())).norm(), 0.1 * Hfd.norm());
}

TEST(FullFemContact, AFreeBoxOnTheFloorIsHeldByItsWeight) {
  test::SyntheticAvatarOptions so;
  so.handles = 0;
  so.two_regions = false;
  Avatar box = test::make_synthetic_avatar(so);
  box.node_role.setConstant(int(NodeRole::Simulated));  // free: nothing pins the bottom
  const auto a = std::make_shared<const Avatar>(box);
  FullFem fem(a);
  const double kappa = 1.0e8, spacing = 0.01;  // 1 cm: 36 samples per face (the 2 mm default: 841)
  fem.add_obstacle({"floor", std::make_shared<geometry::PlaneSdf>(), kappa, spacing});  // y ≤ 0, the box stands on y = 0
  // Closed form: the weight of a 8 × 12 × 8 cm box of density 1000 kg/m³.
  const double weight = 1000.0 * 0.08 * 0.12 * 0.08 * 9.81;
  FullFemReport rep;
  for (int i = 0; i < 600; ++i) {
    rep = fem.step(identity_bones(), {Isometry::Identity()});
    ASSERT_TRUE(rep.converged) << "step " << i;
  }
  ASSERT_EQ(rep.contacts.size(), 1u);
  const FullFemContact& c = rep.contacts[0];
  EXPECT_EQ(c.name, "floor");
  // The bottom: 2 × 2 squares of 4 cm, 8 right triangles with 5.66 cm hypotenuses
  // → n = ⌈5.66 / 1⌉ = 6 subdivisions, 36 samples each; all of it touches.
  EXPECT_EQ(c.active_samples, 8 * 36);
  EXPECT_NEAR(c.contact_area, 0.08 * 0.08, 1e-12);
  EXPECT_NEAR(c.force.y(), weight, 1e-4 * weight);
  EXPECT_LT(std::hypot(c.force.x(), c.force.z()), 1e-6 * weight);
  // The mean sinking is weight / (κ area); the deepest sample sinks at least that
  // (and far less than a millimetre).
  EXPECT_GT(c.max_penetration, weight / (kappa * 0.08 * 0.08));
  EXPECT_LT(c.max_penetration, 1e-3);
}

// Anchors (FullFemAnchor): skin points tied to moving tool points by
// spring–dampers. The energy against anchor.hpp's closed form over the
// asset's skin points (posed bones, mixed barycentric embedding), its
// gradient against finite differences of that closed form and its Hessian
// against (k + c/h) JᵀJ with J by finite differences; the reported force; and
// bad anchors refused naming the anchor.
TEST(FullFemContact, AnchorEnergyGradientHessianAndForce) {
  test::SyntheticAvatarOptions so;
  so.handles = 0;
  const auto a = std::make_shared<const Avatar>(with_embedded_skin(test::make_synthetic_avatar(so)));
  FullFemOptions o;
  o.gravity = Vec3::Zero();
  FullFem with(a, o), without(a, o);
  const auto bones = test::synthetic_motion(*a, 0.1, 0.03, 0.1);
  const Points zero = Points::Zero(a->tet.num_nodes(), 3);
  // Two anchors on distinct skin vertices, tool points a few mm off and moving.
  const int v0 = 3, v1 = int(a->surface_rest.rows()) - 5;
  const std::vector<FullFemAnchor> anchors = {
      {v0, skin_world(*a, v0, zero, bones) + Vec3(0.004, -0.002, 0.001), skin_world(*a, v0, zero, identity_bones()) +
                                                                              Vec3(0.001, 0, 0), 2.0e4, 3.0},
      {v1, skin_world(*a, v1, zero, bones) + Vec3(-0.001, 0.003, 0.002), skin_world(*a, v1, zero, identity_bones()),
       5.0e3, 0.0}};
  with.set_anchors(anchors);
  EXPECT_EQ(with.num_anchors(), 2);
  with.step(bones);
  without.step(bones);
  const Points u1 = with.displacement();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> U(-1e-3, 1e-3);
  Points u = zero;
  std::vector<int> free_of(a->tet.num_nodes(), -1);
  int nfree = 0;
  for (int n = 0; n < a->tet.num_nodes(); ++n)
    if (a->node_role[n] == int(NodeRole::Simulated)) {
      free_of[n] = nfree++;
      for (int i = 0; i < 3; ++i) u(n, i) = U(rng);
    }
  const double h = o.h;
  // Closed form: x_t is the vertex at the rest state and identity bones (the step's start).
  auto anchor_energy = [&](const Points& uu) {
    double E = 0;
    for (const FullFemAnchor& p : anchors) {
      const Vec3 x = skin_world(*a, p.vertex, uu, bones), xt = skin_world(*a, p.vertex, zero, identity_bones());
      E += 0.5 * p.hardness * (x - p.target).squaredNorm() +
           0.5 * p.damping / h * ((x - xt) - (p.target - p.target_prev)).squaredNorm();
    }
    return E;
  };
  VecX g1, g0;
  Eigen::SparseMatrix<double> H1, H0;
  const double E = with.energy(u, &g1, &H1) - without.energy(u, &g0, &H0);
  const double Ec = anchor_energy(u);
  ASSERT_GT(Ec, 0);
  EXPECT_NEAR(E, Ec, 1e-9 * Ec);
  VecX fd(3 * nfree);
  MatX J = MatX::Zero(6, 3 * nfree);  // the two anchors' points over the free DoFs
  const double eps = 1e-7;
  for (int n = 0; n < u.rows(); ++n)
    for (int i = 0; i < 3 && free_of[n] >= 0; ++i) {
      Points up = u, um = u;
      up(n, i) += eps;
      um(n, i) -= eps;
      fd[3 * free_of[n] + i] = (anchor_energy(up) - anchor_energy(um)) / (2 * eps);
      for (int k = 0; k < 2; ++k)
        J.block<3, 1>(3 * k, 3 * free_of[n] + i) =
            (skin_world(*a, anchors[size_t(k)].vertex, up, bones) - skin_world(*a, anchors[size_t(k)].vertex, um, bones)) /
            (2 * eps);
    }
  EXPECT_LT((g1 - g0 - fd).norm(), 1e-6 * fd.norm());
  MatX Hc = MatX::Zero(3 * nfree, 3 * nfree);
  for (int k = 0; k < 2; ++k)
    Hc += (anchors[size_t(k)].hardness + anchors[size_t(k)].damping / h) * J.middleRows<3>(3 * k).transpose() *
          J.middleRows<3>(3 * k);
  EXPECT_LT((MatX(H1) - MatX(H0) - Hc).norm(), 1e-6 * Hc.norm());
  // The force on the body at a second step's end: −Σ ∂E/∂x_v at its final u,
  // x_t now where the first step left the vertex (the targets given again).
  const FullFemReport rep = with.step(bones);
  Vec3 f = Vec3::Zero();
  for (const FullFemAnchor& p : anchors) {
    const Vec3 x = skin_world(*a, p.vertex, with.displacement(), bones), xt = skin_world(*a, p.vertex, u1, bones);
    f -= p.hardness * (x - p.target) + p.damping / h * ((x - xt) - (p.target - p.target_prev));
  }
  ASSERT_GT(f.norm(), 1.0);
  EXPECT_LT((rep.anchor_force - f).norm(), 1e-9 * f.norm()) << rep.anchor_force.transpose() << " vs " << f.transpose();
  for (const auto& [anchor, words] : std::vector<std::pair<FullFemAnchor, std::vector<std::string>>>{
           {{-1, Vec3::Zero(), Vec3::Zero(), 1e3, 1.0}, {"anchor 0", "skin vertex -1"}},
           {{0, Vec3(NAN, 0, 0), Vec3::Zero(), 1e3, 1.0}, {"anchor 0", "target"}},
           {{0, Vec3::Zero(), Vec3::Zero(), 0.0, 1.0}, {"anchor 0", "hardness"}},
           {{0, Vec3::Zero(), Vec3::Zero(), 1e3, -1.0}, {"anchor 0", "damping"}}}) {
    try {
      with.set_anchors({anchor});
      ADD_FAILURE() << "accepted a bad anchor";
    } catch (const Error& e) {
      for (const std::string& w : words) EXPECT_NE(std::string(e.what()).find(w), std::string::npos) << e.what();
    }
  }
}

// The reduced model's face-sampled contact (contact_patch.hpp, without its
// patch: the nodal basis already spans every node) against the reference.
TEST(FullFemContact, ReducedWithAllHandlesAgreesWithTheReferenceUnderContact) {
  test::SyntheticAvatarOptions o;
  o.handles = 0;
  o.two_regions = false;  // lumped node masses use one tet's density: equal only for one region
  const auto a = std::make_shared<const Avatar>(with_embedded_skin(test::make_synthetic_avatar(o)));
  const double r = 0.05, kappa = 2.0e8, h = 1.0 / 60.0;
  auto sphere = std::make_shared<geometry::SphereSdf>(r);

  ModelOptions mo;
  mo.h = h;
  mo.newton.iterations = 100;
  mo.newton.line_search = true;
  mo.newton.gradient_tolerance = 1e-11;
  mo.newton.max_z_step = 0;
  ModelBuilder mb(mo);
  const int body = mb.add_body({"box", a, false});
  SoftTissueOptions so;
  so.mean_dilatation = false;  // the nodal basis is full FEM only with every tet's own volume change
  add_soft_tissue_terms(mb, body, so);
  ContactPatchOptions co;
  co.pressure_stiffness = kappa;
  co.spacing = 0.01;
  co.patch = false;
  co.inner_tolerance = 0;
  mb.add_term(std::make_shared<const ContactPatchTerm>("ball", *a, sphere, Isometry::Identity(), false, co), {body});
  Simulator reduced(mb.build());
  FullFemOptions fo;
  fo.h = h;
  fo.max_iterations = 100;
  FullFem full(a, fo);
  FullFemObstacle ob;
  ob.name = "ball";
  ob.field = sphere;
  ob.pressure_stiffness = kappa;
  ob.spacing = 0.01;
  full.add_obstacle(ob);
  std::vector<int> handle_node;
  for (int n = 0; n < a->tet.num_nodes(); ++n)
    if (a->node_role[n] == int(NodeRole::Simulated)) handle_node.push_back(n);
  ASSERT_EQ(int(handle_node.size()), a->num_handles());

  // The ball comes down onto the top (y = 0.12) from 5 mm above to 2 cm deep while the box bends.
  auto centre = [&](double t) { return Vec3(0.01, 0.12 + r + 0.005 - 0.025 * std::min(t / 0.2, 1.0), 0.004); };
  double worst = 0, peak = 0, force = 0;
  for (int i = 1; i <= 15; ++i) {
    const double t = i * h;
    const auto bones = test::synthetic_motion(*a, t, 0.01, 0.2);
    StepInputs in;
    in.bodies.push_back({bones, {}});
    WorldFrame& f = in.frames["ball"];
    f.pose.translation() = centre(t);
    f.linear_velocity = (centre(t) - centre(t - h)) / h;
    const StepReport rr = reduced.step(in);
    const FullFemReport rf = full.step(bones, {f.pose});
    ASSERT_TRUE(rf.converged) << "step " << i;
    for (int kk = 0; kk < a->num_handles(); ++kk) {
      const Vec3 d = reduced.state().z.segment<3>(3 * kk) - full.displacement().row(handle_node[kk]).transpose();
      worst = std::max(worst, d.norm());
      peak = std::max(peak, full.displacement().row(handle_node[kk]).norm());
    }
    Vec3 fr = Vec3::Zero();
    for (const TermQuantityReport& q : rr.quantities)
      if (q.term == "contact:ball" && q.name == "force") fr = Vec3(q.value[0], q.value[1], q.value[2]);
    EXPECT_LT((fr - rf.contacts[0].force).norm(), 1e-5 * rf.contacts[0].force.norm() + 1e-9) << "step " << i;
    force = std::max(force, rf.contacts[0].force.norm());
  }
  std::cout << "[ reduced vs full, contact ] peak |u| " << peak << " m, peak force " << force
            << " N, largest nodal difference " << worst << " m\n";
  ASSERT_GT(force, 1.0);
  ASSERT_GT(peak, 1e-3);
  EXPECT_LT(worst, 1e-6 * peak);
}

}  // namespace
}  // namespace sflsh
