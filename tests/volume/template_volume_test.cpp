#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <numeric>

#include "sflsh/asset/avatar.hpp"
#include "sflsh/body/body_model_io.hpp"
#include "sflsh/body/procedural_body.hpp"
#include "sflsh/body/smpl_skeleton.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/core/timer.hpp"
#include "sflsh/meshing/tetrahedralize.hpp"
#include "sflsh/volume/body_regions.hpp"
#include "sflsh/volume/correspondence.hpp"
#include "sflsh/volume/shape_volume.hpp"
#include "sflsh/volume/surface_query.hpp"
#include "sflsh/volume/template_volume.hpp"
#include "sflsh/volume/topology_design.hpp"
#include "test_support.hpp"

namespace sflsh {
namespace {

constexpr double kRadius = 0.08, kHalf = 0.25;  // tube radius, half length of its straight part (m)

// A small SMPL-format "body": a capsule (tube of radius 8 cm with round caps)
// around a spine pelvis(y=-0.2) -> spine1(0) -> spine2(0.2); the remaining
// joints sit on their parents (zero-length bones). Weights are hat functions
// along y; the top cap belongs to the head (a skinned joint). Shape
// directions: 0 = radial growth (x, z) * 0.2, 1 = stretch along y * 0.2.
BodyModel capsule_body() {
  const int around = 24;
  std::vector<double> ring_y, ring_r;
  const int cap_rings = 5;
  for (int i = 1; i <= cap_rings; ++i) {  // bottom cap
    const double a = M_PI / 2 * (1.0 - double(i) / (cap_rings + 1));
    ring_y.push_back(-kHalf - kRadius * std::sin(a));
    ring_r.push_back(kRadius * std::cos(a));
  }
  for (int i = 0; i <= 20; ++i) ring_y.push_back(-kHalf + i * 0.025), ring_r.push_back(kRadius);
  for (int i = cap_rings; i >= 1; --i) {  // top cap
    const double a = M_PI / 2 * (1.0 - double(i) / (cap_rings + 1));
    ring_y.push_back(kHalf + kRadius * std::sin(a));
    ring_r.push_back(kRadius * std::cos(a));
  }
  const int R = int(ring_y.size());
  const int V = R * around + 2;
  BodyModel m;
  m.v_template.resize(V, 3);
  for (int r = 0; r < R; ++r)
    for (int k = 0; k < around; ++k) {
      const double t = 2 * M_PI * k / around;
      m.v_template.row(r * around + k) << ring_r[r] * std::cos(t), ring_y[r], ring_r[r] * std::sin(t);
    }
  const int bottom = R * around, top = bottom + 1;
  m.v_template.row(bottom) << 0, -kHalf - kRadius, 0;
  m.v_template.row(top) << 0, kHalf + kRadius, 0;
  std::vector<std::array<int, 3>> f;
  // Counter-clockwise seen from outside: rings go up in y, k goes from +x to +z.
  for (int r = 0; r + 1 < R; ++r)
    for (int k = 0; k < around; ++k) {
      const int a = r * around + k, b = r * around + (k + 1) % around, c = a + around, d = b + around;
      f.push_back({a, c, b});
      f.push_back({b, c, d});
    }
  for (int k = 0; k < around; ++k) {
    f.push_back({bottom, k, (k + 1) % around});
    f.push_back({top, (R - 1) * around + (k + 1) % around, (R - 1) * around + k});
  }
  m.faces.resize(f.size(), 3);
  for (size_t i = 0; i < f.size(); ++i) m.faces.row(i) << f[i][0], f[i][1], f[i][2];

  m.parents.assign(kSmplParents.begin(), kSmplParents.end());
  for (auto n : kSmplJointNames) m.joint_names.emplace_back(n);
  // Joint regressor: pelvis/spine1/spine2 = centroid of the ring at their
  // height; every other joint copies its nearest real ancestor.
  auto ring_of = [&](double y) {
    for (int r = 0; r < R; ++r)
      if (std::abs(ring_y[r] - y) < 1e-9) return r;
    throw Error("no ring");
  };
  std::vector<int> source(kSmplJoints);
  for (int j = 0; j < kSmplJoints; ++j)
    source[j] = (j == 0 || j == 3 || j == 6) ? j : source[m.parents[j]];
  std::vector<Eigen::Triplet<double>> trip;
  for (int j = 0; j < kSmplJoints; ++j) {
    const double y = source[j] == 0 ? -0.2 : source[j] == 3 ? 0.0 : 0.2;
    const int r = ring_of(y);
    for (int k = 0; k < around; ++k) trip.emplace_back(j, r * around + k, 1.0 / around);
  }
  m.J_regressor.resize(kSmplJoints, V);
  m.J_regressor.setFromTriplets(trip.begin(), trip.end());
  m.weights = MatXr::Zero(V, kSmplJoints);
  for (int v = 0; v < V; ++v) {
    const double y = m.v_template(v, 1);
    auto hat = [&](double c) { return std::max(0.0, 1.0 - std::abs(y - c) / 0.2); };
    double w0 = y <= -0.2 ? 1.0 : hat(-0.2), w3 = hat(0.0), w6 = y >= 0.2 ? 1.0 : hat(0.2);
    const double head = std::clamp((y - 0.22) / 0.06, 0.0, 1.0);
    m.weights(v, 0) = w0, m.weights(v, 3) = w3, m.weights(v, 6) = w6 * (1 - head), m.weights(v, 15) = w6 * head;
    m.weights.row(v) /= m.weights.row(v).sum();
  }
  Points radial = m.v_template, stretch = Points::Zero(V, 3);
  radial.col(1).setZero();
  radial *= 0.2;
  stretch.col(1) = 0.2 * m.v_template.col(1);
  m.shapedirs = {radial, stretch};
  m.posedirs = MatX::Zero(3 * V, kSmplPoseFeatures);
  m.source = "test capsule";
  m.validate();
  return m;
}

TemplateOptions coarse_options() {
  TemplateOptions o;
  o.mesh.facet_size = 0.025;
  o.mesh.cell_size = 0.03;
  o.mesh.facet_distance = 0.0015;
  // Uniform sizes (the sizing field has its own test below).
  o.skinned_size_scale = 1.0;
  o.skinned_facet_distance = o.inner_facet_distance = 0.0;
  // The capsule's shapes scale its radius by 1 + 0.2 β0: the design box is the range its tests
  // shape it over (|β| <= 2; at β0 = -3 the tube would shrink to 40 %).
  o.topology.range = 2.0;
  return o;
}

// Built once for the whole suite (a second or two).
const BodyModel& body() {
  static const BodyModel m = capsule_body();
  return m;
}
const TemplateVolume& tmpl() {
  static const TemplateVolume tv = [] {
    TemplateVolume t = build_template_volume(body(), coarse_options());
    std::printf("%s\n", t.report.describe().c_str());
    return t;
  }();
  return tv;
}

TEST(Correspondence, TubeVerticesMapToTheAxisAtTheirHeight) {
  const BodyModel& m = body();
  const Points J = regress_joints(m, m.v_template);
  const auto segs = skeleton_segments(m, m.v_template, J);
  const SurfaceCorrespondence c = compute_surface_correspondence(m, m.v_template, J, segs);
  ASSERT_EQ(c.coefficients.rows(), m.num_vertices());
  EXPECT_LT((c.coefficients.rowwise().sum().array() - 1.0).abs().maxCoeff(), 1e-12);
  for (int v = 0; v < m.num_vertices(); ++v) {
    const double y = m.v_template(v, 1);
    // On the straight part the closest bone point is on the axis at the
    // vertex's height; smoothing keeps it on the axis and (away from the caps,
    // whose vertices all map to the spine ends) at nearly the same height.
    if (std::abs(y) > 0.1) continue;
    EXPECT_NEAR(std::hypot(c.skeleton_points(v, 0), c.skeleton_points(v, 2)), 0.0, 1e-9);
    EXPECT_NEAR(c.skeleton_points(v, 1), y, 2e-3);
    EXPECT_NEAR(c.thickness[v], kRadius, 1e-4);
  }
}

TEST(TemplateVolume, MeshIsValidAndReproducesTheSkin) {
  const TemplateVolume& tv = tmpl();
  const TetQualityReport q = tet_quality_report(tv.tet);
  EXPECT_GT(q.num_tets, 500);
  EXPECT_EQ(q.num_inverted, 0);
  // This coarse test mesh has about one tet across the 4.8 cm soft layer;
  // the slivers left spanning it after perturbation (near 7 deg) are opened
  // by sliver repair (8.04 deg).
  EXPECT_GE(q.min_dihedral_deg, 7.5);
  EXPECT_GT(tv.report.sliver_repair.moves, 0);
  EXPECT_GT(tv.report.sliver_repair.min_dihedral_after, tv.report.sliver_repair.min_dihedral_before);
  EXPECT_LT(double(q.num_below_threshold) / q.num_tets, 0.01);
  EXPECT_LT(tv.report.outer_node_to_skin, 1e-4);
  // facet_distance 1.5 mm here; the skin is reproduced within ~1.5x that.
  EXPECT_LT(tv.report.skin_to_outer_boundary, 3e-3);
  // The shell volume: capsule minus the inner capsule at 0.4 of the radius,
  // roughly (the inner surface is a level set, not exactly a scaled capsule).
  const double outer = M_PI * kRadius * kRadius * 2 * kHalf + 4.0 / 3 * M_PI * std::pow(kRadius, 3);
  EXPECT_GT(q.total_volume, 0.6 * outer);
  EXPECT_LT(q.total_volume, 0.95 * outer);
}

// This case once ran for hours in CGAL Mesh_3, depending on the heap: not the
// facet distance but uninitialized edge pseudo-normals in SurfaceQuery made
// the shell "inside" 0.5 m beyond the skin (scripts/results/cgal_hang.md). It
// builds a second template in the process (after tmpl()), on reused heap.
TEST(TemplateVolume, InnerFacetDistanceCoarsensTheBoneSurfaceOnly) {
  TemplateOptions o = coarse_options();
  o.inner_facet_distance = 4 * o.mesh.facet_distance;
  const TemplateVolume tv = build_template_volume(body(), o);
  const TemplateReport& r = tv.report, &u = tmpl().report;
  std::printf("inner_facet_distance 6 mm: %d tets, %d skin / %d bone-surface nodes (uniform: %d tets, %d / %d)\n",
              tv.tet.num_elements(), r.num_outer_nodes, r.num_inner_nodes, tmpl().tet.num_elements(),
              u.num_outer_nodes, u.num_inner_nodes);
  EXPECT_EQ(r.mesh.quality.num_inverted, 0);
  EXPECT_LT(r.num_inner_nodes, 0.7 * u.num_inner_nodes);
  EXPECT_LT(tv.tet.num_elements(), tmpl().tet.num_elements());
  // The skin keeps its fidelity (same bound as the uniform mesh).
  EXPECT_GT(r.num_outer_nodes, 0.8 * u.num_outer_nodes);
  EXPECT_LT(r.skin_to_outer_boundary, 3e-3);
}

TEST(TemplateVolume, BoundaryRolesDepthsAndWeights) {
  const TemplateVolume& tv = tmpl();
  ASSERT_GT(tv.inner_nodes.size(), 20);
  ASSERT_GT(tv.outer_nodes.size(), 20);
  int skinned = 0, straight = 0, on_level_set = 0;
  for (int i = 0; i < tv.inner_nodes.size(); ++i) {
    const int n = tv.inner_nodes[i];
    const int role = tv.node_role[n];
    EXPECT_TRUE(role == int(NodeRole::Bone) || role == int(NodeRole::Skinned));
    const Vec3 x = tv.tet.nodes.row(n);
    if (std::abs(x.y()) < 0.15) {  // straight part: inner surface at 0.4 of the radius
      // Sliver repair moves a few bone-surface nodes off the level set, by at
      // most 30 % of an edge; the node depth follows the node.
      const double r = std::hypot(x.x(), x.z());
      EXPECT_NEAR(r, 0.4 * kRadius, 8e-3);
      EXPECT_NEAR(tv.node_depth[n], r / kRadius, 0.03);
      ++straight;
      on_level_set += std::abs(r - 0.4 * kRadius) < 2e-3;
    }
  }
  EXPECT_GT(on_level_set, 0.7 * straight);
  for (int i = 0; i < tv.outer_nodes.size(); ++i) EXPECT_NEAR(tv.node_depth[tv.outer_nodes[i]], 1.0, 1e-12);
  for (int n = 0; n < tv.tet.num_nodes(); ++n) {
    EXPECT_NEAR(tv.node_weights.row(n).sum(), 1.0, 1e-12);
    EXPECT_GE(tv.node_weights.row(n).minCoeff(), 0.0);
    skinned += tv.node_role[n] == int(NodeRole::Skinned);
    // Skinned nodes belong to the "head" cap: paths from the spine end at
    // y = 0.2 fan out into it, so their interior nodes reach slightly below.
    if (tv.node_role[n] == int(NodeRole::Skinned)) {
      EXPECT_GT(tv.tet.nodes(n, 1), 0.16);
    }
  }
  EXPECT_GT(skinned, 0);
  EXPECT_LT(tv.report.max_path_residual, 5e-3);
}

TEST(ShapeVolume, SameTopologyForTwoShapesAndBlendShapesAlongPaths) {
  const TemplateVolume& tv = tmpl();
  const VecX b1 = (VecX(2) << 1.0, 0.0).finished(), b2 = (VecX(2) << -0.5, 1.0).finished();
  // The placement rule itself, without the interior optimization (tested below).
  ShapeOptions placement_only;
  placement_only.smoothing.passes = 0;
  const ShapedVolume s1 = shape_volume(tv, body(), b1, ThicknessMap::uniform(), placement_only);
  const ShapedVolume s2 = shape_volume(tv, body(), b2, ThicknessMap::uniform(), placement_only);
  EXPECT_TRUE(s1.avatar.tet.elements == tv.tet.elements);
  EXPECT_TRUE(s2.avatar.tet.elements == tv.tet.elements);
  EXPECT_EQ(s1.report.quality.num_inverted, 0);
  // With a uniform thickness map the nodes are template + Σ β node_shapedirs
  // up to the path-fit residual (< 5 mm) riding with the path: it changes by
  // at most |residual| times the path's relative length change (20 %).
  for (const auto* s : {&s1, &s2}) {
    Points expect = tv.tet.nodes;
    for (int b = 0; b < 2; ++b) expect += s->avatar.betas[b] * tv.node_shapedirs[b];
    for (int n = 0; n < tv.tet.num_nodes(); ++n)
      EXPECT_LE((s->avatar.tet.nodes.row(n) - expect.row(n)).norm(), 0.25 * tv.node_residual.row(n).norm() + 1e-12);
  }
  // β0 = +1 grows the tube radially by 20 %: outer nodes on the straight part
  // move from r to 1.2 r, the bone surface (depth 0.4) likewise.
  for (int i = 0; i < tv.outer_nodes.size(); ++i) {
    const int n = tv.outer_nodes[i];
    if (std::abs(tv.tet.nodes(n, 1)) > 0.15) continue;
    EXPECT_NEAR(std::hypot(s1.avatar.tet.nodes(n, 0), s1.avatar.tet.nodes(n, 2)),
                1.2 * std::hypot(tv.tet.nodes(n, 0), tv.tet.nodes(n, 2)), 1e-6);
  }
}

TEST(ShapeVolume, ThicknessMapMovesTheBoneSurfaceNotTheSkin) {
  const TemplateVolume& tv = tmpl();
  ThicknessMap thick;
  for (const auto& r : body_region_names()) thick.scale[r] = 1.3;
  const VecX beta = VecX::Zero(2);
  // The placement rule itself, without the interior optimization (checked after).
  ShapeOptions placement_only;
  placement_only.smoothing.passes = 0;
  const ShapedVolume s = shape_volume(tv, body(), beta, thick, placement_only);
  EXPECT_EQ(s.report.quality.num_inverted, 0);
  // Thickening a layer about one tet thick by 30 % squeezes some tets
  // tangentially; the few that would drop below 2 deg keep a smaller scale.
  EXPECT_LT(s.report.num_relaxed_nodes, tv.tet.num_nodes() / 10) << s.report.describe();
  EXPECT_GE(s.report.quality.min_dihedral_deg, 2.0);
  for (int i = 0; i < tv.outer_nodes.size(); ++i) {
    const int n = tv.outer_nodes[i];
    EXPECT_LT((s.avatar.tet.nodes.row(n) - tv.tet.nodes.row(n)).norm(), 1e-12);
  }
  int checked = 0;
  for (int i = 0; i < tv.inner_nodes.size(); ++i) {
    const int n = tv.inner_nodes[i];
    if (std::abs(tv.tet.nodes(n, 1)) > 0.1 || tv.node_role[n] != int(NodeRole::Bone)) continue;
    // Soft layer 0.6 R -> 0.78 R: the bone surface goes from 0.4 R to 0.22 R
    // (from r to R - 1.3 (R - r) for nodes sliver repair moved off 0.4 R).
    const double r = std::hypot(tv.tet.nodes(n, 0), tv.tet.nodes(n, 2));
    EXPECT_NEAR(std::hypot(s.avatar.tet.nodes(n, 0), s.avatar.tet.nodes(n, 2)), kRadius - 1.3 * (kRadius - r), 2.5e-3);
    ++checked;
  }
  EXPECT_GT(checked, 5);

  // With the interior optimization (default options): the tets the thickened layer flattened
  // get back to min(8 deg, the template's minimum), skin nodes stay on the skin surface, bone
  // nodes slide across their (radial) paths: their radius changes only to second order.
  const double q0 = tet_quality_report(tv.tet).min_dihedral_deg;
  ASSERT_LT(s.report.quality.min_dihedral_deg, std::min(8.0, q0)) << "nothing for the optimization to do";
  const ShapedVolume o = shape_volume(tv, body(), beta, thick);
  EXPECT_EQ(o.report.quality.num_inverted, 0);
  EXPECT_GE(o.report.quality.min_dihedral_deg, std::min(8.0, q0) - 1e-9) << o.report.describe();
  EXPECT_GT(o.report.smoothing.nodes_moved, 0);
  const SurfaceQuery skin(body().v_template, body().faces);
  int slid = 0;
  for (int i = 0; i < tv.outer_nodes.size(); ++i) {  // a moved skin node is projected onto the skin
    const int n = tv.outer_nodes[i];
    const bool moved = (o.avatar.tet.nodes.row(n) - s.avatar.tet.nodes.row(n)).norm() > 0;
    slid += moved;
    const double d = skin.distance(o.avatar.tet.nodes.row(n).transpose());
    EXPECT_LT(d, moved ? 1e-9 : skin.distance(s.avatar.tet.nodes.row(n).transpose()) + 1e-12);
  }
  EXPECT_LE(slid, o.report.skin_smoothing.nodes_moved);
  for (int i = 0; i < tv.inner_nodes.size(); ++i) {
    const int n = tv.inner_nodes[i];
    const double moved = (o.avatar.tet.nodes.row(n) - s.avatar.tet.nodes.row(n)).norm();
    if (std::abs(tv.tet.nodes(n, 1)) > 0.1 || moved == 0) continue;
    const double r0 = std::hypot(s.avatar.tet.nodes(n, 0), s.avatar.tet.nodes(n, 2));
    EXPECT_LT(std::abs(std::hypot(o.avatar.tet.nodes(n, 0), o.avatar.tet.nodes(n, 2)) - r0), moved * moved / r0 + 1e-9);
  }
}

TEST(ShapeVolume, NoInvertedTetsOverTheBetaRange) {
  const TemplateVolume& tv = tmpl();
  const double q0 = tet_quality_report(tv.tet).min_dihedral_deg;
  ThicknessMap thick = ThicknessMap::defaults();
  for (const auto& r : body_region_names()) thick.scale[r] = 1.25;
  for (const auto& beta : {VecX((VecX(2) << 2.0, 0.0).finished()), VecX((VecX(2) << -2.0, 0.0).finished()),
                           VecX((VecX(2) << 0.0, 2.0).finished()), VecX((VecX(2) << 0.0, -2.0).finished()),
                           VecX((VecX(2) << 1.7, -1.3).finished()), VecX((VecX(2) << -1.9, 1.1).finished())}) {
    for (const ThicknessMap& map : {ThicknessMap::uniform(), thick}) {
      const ShapedVolume s = shape_volume(tv, body(), beta, map);
      EXPECT_EQ(s.report.quality.num_inverted, 0) << beta.transpose();
      // The shape only moves nodes (with the interior optimization and skin sliding on):
      // the template's tets, regions and node count for every shape.
      EXPECT_TRUE(s.avatar.tet.elements == tv.tet.elements) << beta.transpose();
      EXPECT_TRUE(s.avatar.tet_region == tv.tet_region) << beta.transpose();
      EXPECT_EQ(s.avatar.tet.num_nodes(), tv.tet.num_nodes()) << beta.transpose();
      EXPECT_GT(s.report.quality.min_volume, 0.0);
      // Radial growth/stretch by up to 40 % distorts tets a little; the
      // thickness map never takes one below 2 deg (ShapeOptions).
      EXPECT_GE(s.report.quality.min_dihedral_deg, std::min(2.0, 0.5 * q0)) << beta.transpose();
    }
  }
}

TEST(ShapeVolume, AvatarGeometryFields) {
  const TemplateVolume& tv = tmpl();
  const VecX beta = (VecX(2) << 0.5, -0.5).finished();
  const ShapedVolume s = shape_volume(tv, body(), beta);
  const Avatar& a = s.avatar;
  const int N = a.tet.num_nodes(), T = a.tet.num_elements(), V = body().num_vertices();
  ASSERT_EQ(a.surface_tet.size(), V);
  ASSERT_EQ(a.surface_bary.rows(), V);
  // Embedding: inside vertices are reproduced exactly, the others within the
  // skin fidelity.
  for (int v = 0; v < V; ++v) {
    Vec3 y = Vec3::Zero();
    for (int i = 0; i < 4; ++i) y += a.surface_bary(v, i) * a.tet.nodes.row(a.tet.elements(a.surface_tet[v], i)).transpose();
    EXPECT_GE(a.surface_bary.row(v).minCoeff(), 0.0);
    EXPECT_NEAR(a.surface_bary.row(v).sum(), 1.0, 1e-12);
    const double err = (y - a.surface_rest.row(v).transpose()).norm();
    EXPECT_LT(err, 4e-3);  // coarse test mesh (facet_distance 1.5 mm)
    if (s.report.num_embedded_outside == 0) {
      EXPECT_LT(err, 1e-6);
    }
  }
  EXPECT_LT(s.report.max_embedding_distance, 4e-3);
  EXPECT_EQ(a.tet_region.size(), T);
  EXPECT_EQ(a.materials.size(), body_region_names().size());
  ASSERT_EQ(a.tet_frames.rows(), T);
  for (int t = 0; t < T; ++t) {
    const Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> R(a.tet_frames.row(t).data());
    EXPECT_LT((R * R.transpose() - Mat3::Identity()).norm(), 1e-9);
    EXPECT_NEAR(R.determinant(), 1.0, 1e-9);
  }
  EXPECT_EQ(a.node_weights.rows(), N);
  EXPECT_EQ(a.node_role.size(), N);
  EXPECT_EQ(a.joints_rest.rows(), kSmplJoints);
  // Capsules: spine segments, radius ≈ tube radius (1.1 R after β0 = 0.5).
  ASSERT_FALSE(a.capsules.empty());
  for (const auto& c : a.capsules) EXPECT_NEAR(c.radius, 1.1 * kRadius, 0.01);
}

// It aborted at process exit ("corrupted size vs. prev_size") until save_template_volume stopped
// feeding three values to a two-wide row through Eigen's comma initializer (a heap write past
// the segment table's last row; Eigen checks the count only in debug builds).
TEST(TemplateVolume, CacheRoundTripAndCorruptFile) {
  const TemplateVolume& tv = tmpl();
  test::TempDir dir;
  const std::string path = dir.file("template.h5");
  save_template_volume(tv, path);
  const TemplateVolume back = load_template_volume(path);
  EXPECT_EQ(back.model_hash, tv.model_hash);
  EXPECT_TRUE(back.tet.elements == tv.tet.elements);
  EXPECT_EQ((back.tet.nodes - tv.tet.nodes).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ((back.node_weights - tv.node_weights).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_TRUE(back.node_role == tv.node_role);
  ASSERT_EQ(back.node_shapedirs.size(), tv.node_shapedirs.size());
  EXPECT_EQ((back.node_shapedirs[1] - tv.node_shapedirs[1]).cwiseAbs().maxCoeff(), 0.0);
  ASSERT_EQ(back.segments.size(), tv.segments.size());
  // Shaping from the cache gives the same nodes.
  const VecX beta = (VecX(2) << 0.3, 0.7).finished();
  EXPECT_EQ((shape_volume(back, body(), beta).avatar.tet.nodes - shape_volume(tv, body(), beta).avatar.tet.nodes)
                .cwiseAbs()
                .maxCoeff(),
            0.0);
  // A truncated file is rejected with the file name in the message.
  const std::string bad = dir.file("truncated.h5");
  {
    std::ifstream in(path, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), {});
    std::ofstream(bad, std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  }
  try {
    load_template_volume(bad);
    ADD_FAILURE() << "truncated cache accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("truncated.h5"), std::string::npos) << e.what();
  }
  // A model that is not the one the template was built from is rejected.
  BodyModel other = body();
  other.v_template(0, 0) += 1e-3;
  EXPECT_THROW(shape_volume(tv, other, VecX()), Error);
}

// The design shapes of the topology design, by hand for a model with 2 shape directions.
TEST(TopologyDesign, DesignShapesAreZeroEachDirectionAloneTheTwoExtremesAndTheAlternations) {
  TopologyDesignOptions o;
  o.range = 3;
  const auto shapes = topology_design_shapes(2, o);
  const std::vector<std::pair<std::string, std::vector<double>>> expect = {
      {"zero", {0, 0}},          {"beta0=-3", {-3, 0}}, {"beta0=+3", {3, 0}},        {"beta1=-3", {0, -3}},
      {"beta1=+3", {0, 3}},      {"all -3", {-3, -3}},  {"all +3", {3, 3}},          {"alternating +-", {3, -3}},
      {"alternating -+", {-3, 3}}};
  ASSERT_EQ(shapes.size(), expect.size());
  for (size_t i = 0; i < expect.size(); ++i) {
    EXPECT_EQ(shapes[i].first, expect[i].first);
    EXPECT_EQ(shapes[i].second, Eigen::Map<const VecX>(expect[i].second.data(), 2)) << shapes[i].first;
  }
  o.directions = 1;  // only the first direction set, also in the extremes; 12 betas: 10 zeros each
  const auto one = topology_design_shapes(12, o);
  ASSERT_EQ(one.size(), 5u);  // zero, beta0=-3, beta0=+3, all -3, all +3 (no alternation with one direction)
  EXPECT_EQ(one[3].second[0], -3);
  EXPECT_EQ(one[3].second.tail(11).cwiseAbs().maxCoeff(), 0);
  o.directions = 0;
  EXPECT_TRUE(topology_design_shapes(2, o).empty());
}

// The template stage ran its design on the capsule (9 design shapes) and left a mesh whose
// tets are valid at β = 0 with every node in a tet and per-node fields of one length.
TEST(TopologyDesign, TemplateCarriesItsDesignReport) {
  const TemplateVolume& tv = tmpl();
  const TopologyDesignReport& r = tv.report.topology;
  std::printf("%s\n", r.describe().c_str());
  ASSERT_EQ(r.shapes.size(), 9u);
  EXPECT_EQ(r.min_dihedral_after.size(), 9u);
  EXPECT_EQ(tv.tet.num_nodes(), r.nodes_before - r.ears_removed);
  EXPECT_EQ(tv.tet.num_elements(),
            r.tets_before - r.caps_removed_at_corners - r.caps_removed + r.flips_2_3 - r.flips_3_2 - r.ears_removed);
  EXPECT_EQ(r.corners_screened, 4);
  EXPECT_EQ(tet_quality_report(tv.tet).num_inverted, 0);
  const int N = tv.tet.num_nodes();
  EXPECT_EQ(tv.node_depth.size(), N);
  EXPECT_EQ(tv.node_weights.rows(), N);
  EXPECT_EQ(tv.node_shapedirs[0].rows(), N);
  EXPECT_EQ(tv.tet_region.size(), tv.tet.num_elements());
  std::vector<int> uses(size_t(N), 0);
  for (int t = 0; t < tv.tet.num_elements(); ++t)
    for (int c = 0; c < 4; ++c) ++uses[size_t(tv.tet.elements(t, c))];
  EXPECT_EQ(std::count(uses.begin(), uses.end(), 0), 0);
}

// keep_template_nodes (ear removal at the template stage): a node appended to every per-node
// field, in no tet, goes; every other node keeps its values and the tets their nodes. A node a
// tet uses cannot go.
TEST(TopologyDesign, KeepTemplateNodesDropsANodeFromEveryField) {
  const TemplateVolume& tv = tmpl();
  const int N = tv.tet.num_nodes();
  TemplateVolume big = tv;
  auto grow = [](auto& m) {
    m.conservativeResize(m.rows() + 1, Eigen::NoChange);
    m.row(m.rows() - 1).setConstant(7);
  };
  grow(big.tet.nodes), grow(big.node_face_bary), grow(big.node_skeleton_coefficients), grow(big.node_residual),
      grow(big.node_weights);
  for (auto& d : big.node_shapedirs) grow(d);
  auto grow_vec = [](auto& v, auto value) {
    v.conservativeResize(v.size() + 1);
    v[v.size() - 1] = value;
  };
  grow_vec(big.node_face, 0), grow_vec(big.node_depth, 0.5), grow_vec(big.node_segment, 0),
      grow_vec(big.node_role, 0), grow_vec(big.outer_nodes, N);
  if (big.node_posedirs.size() > 0) big.node_posedirs.conservativeResize(3 * (N + 1), Eigen::NoChange);
  std::vector<int> kept(static_cast<size_t>(N));
  std::iota(kept.begin(), kept.end(), 0);
  keep_template_nodes(big, kept);
  EXPECT_EQ(big.tet.nodes, tv.tet.nodes);
  EXPECT_EQ(big.tet.elements, tv.tet.elements);
  EXPECT_EQ(big.outer_nodes, tv.outer_nodes);
  EXPECT_EQ(big.node_weights, tv.node_weights);
  EXPECT_EQ(big.node_shapedirs[1], tv.node_shapedirs[1]);
  EXPECT_EQ(big.node_depth, tv.node_depth);
  TemplateVolume t2 = tv;
  std::vector<int> no_first(kept.begin() + 1, kept.end());
  EXPECT_THROW(keep_template_nodes(t2, no_first), Error);
}

// The real default body; slow (tens of seconds), run with
// --gtest_also_run_disabled_tests to get the figures for the report.
TEST(TemplateVolume, DISABLED_ProceduralBody) {
  const BodyModel m = make_procedural_body();
  Timer t;
  const TemplateVolume tv = build_template_volume(m, TemplateOptions{});
  std::printf("procedural body, %d skin vertices: template stage %.1f s\n%s\n", m.num_vertices(), t.seconds(),
              tv.report.describe().c_str());
  EXPECT_EQ(tv.report.mesh.quality.num_inverted, 0);
  t.reset();
  VecX beta = VecX::Zero(m.num_betas());
  beta[0] = 1.0;
  const ShapedVolume s = shape_volume(tv, m, beta);
  std::printf("shape stage %.2f s\n%s\n", t.seconds(), s.report.describe().c_str());
  std::vector<int> per_region(body_region_names().size(), 0);
  for (int i = 0; i < s.avatar.tet_region.size(); ++i) ++per_region[s.avatar.tet_region[i]];
  for (size_t r = 0; r < per_region.size(); ++r) std::printf("  %s: %d tets\n", body_region_names()[r].c_str(), per_region[r]);
  std::printf("  %zu capsules\n", s.avatar.capsules.size());
}

}  // namespace
}  // namespace sflsh
