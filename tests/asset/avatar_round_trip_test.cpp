// A complete avatar-file round trip with a distinct, non-default value in
// every field (so a swapped or dropped field cannot go unnoticed): different
// elastic and inertia cubatures, anisotropic moduli, two regions with two
// densities, pose blend shapes, two capsules, mixed node roles, rotated frames.
// Plus the mass integrated by the read inertia cubature, Σ ρ·w, against the
// mesh mass Σ ρ_t V_t computed here from the tet volumes.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include <Eigen/Geometry>

#include "sflsh/asset/avatar_file.hpp"
#include "sflsh/body/smpl_skeleton.hpp"
#include "test_support.hpp"

using namespace sflsh;

namespace {

// Two unit-ish cubes (regions 0 and 1), each split into 5 tets.
void add_cube(Avatar& a, const Vec3& origin, double edge, int region) {
  const int base = int(a.tet.nodes.rows());
  a.tet.nodes.conservativeResize(base + 8, 3);
  for (int c = 0; c < 8; ++c)
    a.tet.nodes.row(base + c) = (origin + edge * Vec3(c & 1, (c >> 1) & 1, (c >> 2) & 1)).transpose();
  const int tets[5][4] = {{0, 1, 2, 4}, {1, 3, 2, 7}, {1, 2, 4, 7}, {1, 4, 5, 7}, {2, 4, 7, 6}};
  for (const auto& t : tets) {
    const int e = int(a.tet.elements.rows());
    a.tet.elements.conservativeResize(e + 1, 4);
    for (int c = 0; c < 4; ++c) a.tet.elements(e, c) = base + t[c];
    a.tet_region.conservativeResize(e + 1);
    a.tet_region[e] = region;
  }
}

double tet_volume(const Avatar& a, int t) {
  Mat3 D;
  for (int c = 1; c < 4; ++c)
    D.col(c - 1) = (a.tet.nodes.row(a.tet.elements(t, c)) - a.tet.nodes.row(a.tet.elements(t, 0))).transpose();
  return std::abs(D.determinant()) / 6;
}

Avatar distinct_avatar() {
  Avatar a;
  a.betas = VecX::LinSpaced(10, -1.5, 2.25);
  a.model_hash = "0123456789abcdef";
  a.model_source = "tests/some_model.npz";
  a.joints_rest = Points::Random(24, 3);
  a.parents.assign(kSmplParents.begin(), kSmplParents.end());
  for (auto n : kSmplJointNames) a.joint_names.emplace_back(n);
  a.capsules.push_back({3, Vec3(0.1, 0.2, 0.3), Vec3(0.4, 0.5, 0.6), 0.07});
  a.capsules.push_back({17, Vec3(-0.1, 0.25, 0.35), Vec3(0.45, -0.55, 0.65), 0.03});

  add_cube(a, Vec3(0, 0, 0), 0.1, 0);
  add_cube(a, Vec3(0.3, 0.05, -0.02), 0.13, 1);
  const int N = int(a.tet.nodes.rows()), T = int(a.tet.elements.rows());
  a.tet_frames.resize(T, 9);
  for (int t = 0; t < T; ++t) {
    const Mat3 R = Eigen::AngleAxisd(0.3 + 0.2 * t, Vec3(1, 2, 3).normalized()).toRotationMatrix();
    for (int i = 0; i < 9; ++i) a.tet_frames(t, i) = R(i / 3, i % 3);
  }
  a.node_weights = MatXr::Random(N, 24).cwiseAbs();
  a.node_role.resize(N);
  for (int i = 0; i < N; ++i) a.node_role[i] = i % 3;
  a.surface_nodes.resize(6);
  a.surface_nodes << 1, 3, 5, 8, 11, 15;

  a.surface_rest = a.tet.nodes.topRows(10) + Points::Constant(10, 3, 0.001);
  a.surface_faces.resize(3, 3);
  a.surface_faces << 0, 1, 2, 3, 4, 5, 7, 8, 9;
  a.surface_weights = MatXr::Random(10, 24).cwiseAbs();
  a.surface_posedirs = MatXr::Random(30, 207);
  a.surface_tet.resize(10);
  for (int v = 0; v < 10; ++v) a.surface_tet[v] = (3 * v) % T;
  a.surface_bary = MatXr::Random(10, 4).cwiseAbs();

  RegionMaterial torso{"torso", 3.1e4, 1.2e4, 2.3e4, 0.41, 1.7e3, 1050};
  RegionMaterial thigh{"thigh", 4.4e4, 0.9e4, 1.6e4, 0.37, 2.9e3, 980};
  a.materials = {torso, thigh};

  a.handles.resize(3, 3);
  a.handles << 0.05, 0.05, 0.05, 0.35, 0.1, 0.0, 0.4, 0.15, 0.08;
  MatXr W = MatXr::Zero(N, 3);
  for (int i = 0; i < N; ++i)
    if (a.node_role[i] == 0) W.row(i) << 0.1 + 0.01 * i, 0.2, 0.05 * (i % 4);
  a.W = W.sparseView();

  // Elastic: 4 samples with made-up weights; inertia: one per tet, weight = its volume.
  a.elastic.elements.resize(4);
  a.elastic.elements << 2, 7, 0, 9;
  a.elastic.barycentric = MatXr::Random(4, 4).cwiseAbs();
  a.elastic.weights.resize(4);
  a.elastic.weights << 1e-4, 3e-4, 2e-4, 5e-4;
  a.inertia.elements = VecXi::LinSpaced(T, T - 1, 0);
  a.inertia.barycentric.resize(T, 4);
  a.inertia.weights.resize(T);
  for (int s = 0; s < T; ++s) {
    a.inertia.barycentric.row(s) << 0.1, 0.2, 0.3, 0.4;
    a.inertia.weights[s] = tet_volume(a, a.inertia.elements[s]);
  }
  return a;
}

void expect_same_material(const RegionMaterial& b, const RegionMaterial& a) {
  EXPECT_EQ(b.name, a.name);
  EXPECT_EQ(b.young_along, a.young_along) << a.name;
  EXPECT_EQ(b.young_through, a.young_through) << a.name;
  EXPECT_EQ(b.young_around, a.young_around) << a.name;
  EXPECT_EQ(b.poisson, a.poisson) << a.name;
  EXPECT_EQ(b.fung_c, a.fung_c) << a.name;
  EXPECT_EQ(b.density, a.density) << a.name;
}

void expect_same_cubature(const Cubature& b, const Cubature& a) {
  EXPECT_EQ(b.elements, a.elements);
  EXPECT_EQ(b.barycentric, a.barycentric);
  EXPECT_EQ(b.weights, a.weights);
}

}  // namespace

TEST(AvatarRoundTrip, EveryFieldSurvivesWithDistinctValues) {
  test::TempDir tmp;
  const Avatar a = distinct_avatar();
  // The fixture must really be distinct where a mix-up could hide.
  ASSERT_NE(a.elastic.size(), a.inertia.size());
  for (const auto& m : a.materials) {
    ASSERT_NE(m.young_along, m.young_through);
    ASSERT_NE(m.young_through, m.young_around);
    ASSERT_NE(m.young_along, m.young_around);
  }
  ASSERT_NE(a.materials[0].density, a.materials[1].density);

  write_avatar(a, tmp.file("a.h5"));
  const Avatar b = read_avatar(tmp.file("a.h5"));
  EXPECT_EQ(b.format_version, a.format_version);
  EXPECT_EQ(b.betas, a.betas);
  EXPECT_EQ(b.model_hash, a.model_hash);
  EXPECT_EQ(b.model_source, a.model_source);
  EXPECT_EQ(b.joints_rest, a.joints_rest);
  EXPECT_EQ(b.parents, a.parents);
  EXPECT_EQ(b.joint_names, a.joint_names);
  ASSERT_EQ(b.capsules.size(), a.capsules.size());
  for (size_t i = 0; i < a.capsules.size(); ++i) {
    EXPECT_EQ(b.capsules[i].bone, a.capsules[i].bone);
    EXPECT_EQ(b.capsules[i].p0, a.capsules[i].p0);
    EXPECT_EQ(b.capsules[i].p1, a.capsules[i].p1);
    EXPECT_EQ(b.capsules[i].radius, a.capsules[i].radius);
  }
  EXPECT_EQ(b.surface_rest, a.surface_rest);
  EXPECT_EQ(b.surface_faces, a.surface_faces);
  EXPECT_EQ(b.surface_weights, a.surface_weights);
  EXPECT_EQ(b.surface_posedirs, a.surface_posedirs);
  EXPECT_EQ(b.surface_tet, a.surface_tet);
  EXPECT_EQ(b.surface_bary, a.surface_bary);
  EXPECT_EQ(b.tet.nodes, a.tet.nodes);
  EXPECT_EQ(b.tet.elements, a.tet.elements);
  EXPECT_EQ(b.node_weights, a.node_weights);
  EXPECT_EQ(b.node_role, a.node_role);
  EXPECT_EQ(b.surface_nodes, a.surface_nodes);
  EXPECT_EQ(b.tet_region, a.tet_region);
  EXPECT_EQ(b.tet_frames, a.tet_frames);
  ASSERT_EQ(b.materials.size(), a.materials.size());
  for (size_t r = 0; r < a.materials.size(); ++r) expect_same_material(b.materials[r], a.materials[r]);
  EXPECT_EQ(b.handles, a.handles);
  EXPECT_EQ(MatXr(b.W), MatXr(a.W));
  expect_same_cubature(b.elastic, a.elastic);
  expect_same_cubature(b.inertia, a.inertia);
}

TEST(AvatarRoundTrip, InertiaCubatureOfTheReadFileCarriesTheMeshMass) {
  test::TempDir tmp;
  const Avatar a = distinct_avatar();
  // Mesh mass from the tet volumes and the region densities, here.
  double mesh_mass = 0;
  for (int t = 0; t < a.tet.num_elements(); ++t) mesh_mass += (a.tet_region[t] == 0 ? 1050.0 : 980.0) * tet_volume(a, t);
  // Two 0.1 m and 0.13 m cubes: ρ₀ · 0.001 + ρ₁ · 0.002197.
  EXPECT_NEAR(mesh_mass, 1050 * 1e-3 + 980 * 0.13 * 0.13 * 0.13, 1e-12);
  write_avatar(a, tmp.file("a.h5"));
  const Avatar b = read_avatar(tmp.file("a.h5"));
  double cubature_mass = 0;  // Σ ρ(region of the sample's tet) · w
  for (int s = 0; s < b.inertia.size(); ++s)
    cubature_mass += b.materials[b.tet_region[b.inertia.elements[s]]].density * b.inertia.weights[s];
  EXPECT_NEAR(cubature_mass, mesh_mass, 1e-12 * mesh_mass);
}

TEST(AvatarRoundTrip, ValidationRejectsEveryIndexOneBeyondItsRange) {
  // Each index set exactly to its bound (one past the last valid value).
  const Avatar ok = distinct_avatar();
  const int N = int(ok.tet.nodes.rows()), T = int(ok.tet.elements.rows()), V = int(ok.surface_rest.rows());
  const int R = int(ok.materials.size());
  struct Case {
    const char* dataset;
    std::function<void(Avatar&)> edit;
  } cases[] = {
      {"/tet/region", [&](Avatar& a) { a.tet_region[3] = R; }},
      {"/tet/elements", [&](Avatar& a) { a.tet.elements(2, 1) = N; }},
      {"/surface/tet", [&](Avatar& a) { a.surface_tet[4] = T; }},
      {"/surface/faces", [&](Avatar& a) { a.surface_faces(1, 2) = V; }},
      {"/tet/surface_nodes", [&](Avatar& a) { a.surface_nodes[0] = N; }},
      {"/tet/node_role", [&](Avatar& a) { a.node_role[5] = 3; }},
      {"/cubature/elastic", [&](Avatar& a) { a.elastic.elements[1] = T; }},
      {"/cubature/inertia", [&](Avatar& a) { a.inertia.elements[0] = T; }},
  };
  for (const auto& c : cases) {
    Avatar a = ok;
    c.edit(a);
    test::expect_error([&] { validate_avatar(a, "x.h5"); }, {"x.h5", c.dataset});
  }
  EXPECT_NO_THROW(validate_avatar(ok, "ok.h5"));
}
