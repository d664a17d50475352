// Primitive surfaces against their SDFs (every vertex on the zero level, every
// face's normal along the field's gradient), closedness (each directed edge
// once, its reverse once), and enclosed volumes against closed forms.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <utility>

#include "sflsh/geometry/primitive_meshes.hpp"
#include "test_support.hpp"

namespace sflsh {
namespace {

using geometry::PrimitiveMesh;
constexpr double kPi = 3.14159265358979323846;

/// Σ over faces of det(a, b, c)/6 (tetrahedra from the origin).
double signed_volume(const PrimitiveMesh& m) {
  double v = 0;
  for (Eigen::Index f = 0; f < m.faces.rows(); ++f) {
    const Vec3 a = m.vertices.row(m.faces(f, 0)), b = m.vertices.row(m.faces(f, 1)), c = m.vertices.row(m.faces(f, 2));
    v += a.dot(b.cross(c)) / 6.0;
  }
  return v;
}

/// Every vertex on φ = 0, every face's normal within 60° of ∇φ at its centroid.
void expect_on_surface_and_outward(const PrimitiveMesh& m, const geometry::Sdf& sdf, double tol = 1e-9) {
  ASSERT_GT(m.faces.rows(), 0);
  for (Eigen::Index i = 0; i < m.vertices.rows(); ++i)
    ASSERT_LT(std::abs(sdf.distance(m.vertices.row(i).transpose())), tol) << "vertex " << i;
  for (Eigen::Index f = 0; f < m.faces.rows(); ++f) {
    const Vec3 a = m.vertices.row(m.faces(f, 0)), b = m.vertices.row(m.faces(f, 1)), c = m.vertices.row(m.faces(f, 2));
    const Vec3 n = (b - a).cross(c - a);
    ASSERT_GT(n.norm(), 0) << "degenerate face " << f;
    ASSERT_GT(n.normalized().dot(sdf.evaluate((a + b + c) / 3).gradient), 0.5) << "face " << f;
  }
}

/// Closed and consistently oriented: every directed edge once, its reverse once.
void expect_closed(const PrimitiveMesh& m) {
  std::map<std::pair<int, int>, int> edges;
  for (Eigen::Index f = 0; f < m.faces.rows(); ++f)
    for (int k = 0; k < 3; ++k) ++edges[{m.faces(f, k), m.faces(f, (k + 1) % 3)}];
  for (const auto& [e, count] : edges) {
    ASSERT_EQ(count, 1) << e.first << "-" << e.second;
    ASSERT_EQ(edges.count({e.second, e.first}), 1u) << "open edge " << e.first << "-" << e.second;
  }
  // Every vertex is used.
  std::vector<bool> used(size_t(m.vertices.rows()), false);
  for (Eigen::Index i = 0; i < m.faces.size(); ++i) used[size_t(m.faces.data()[i])] = true;
  for (size_t i = 0; i < used.size(); ++i) EXPECT_TRUE(used[i]) << "vertex " << i;
}

TEST(PrimitiveMeshes, SphereOnItsSdfClosedAndConverging) {
  const double r = 0.37, exact = 4.0 / 3.0 * kPi * r * r * r;
  double previous_error = 0;
  for (int res : {8, 16, 32, 64}) {
    const PrimitiveMesh m = geometry::sphere_mesh(r, res);
    expect_on_surface_and_outward(m, geometry::SphereSdf(r));
    expect_closed(m);
    const double v = signed_volume(m);
    EXPECT_GT(v, 0);
    EXPECT_LT(v, exact);  // inscribed
    const double error = exact - v;
    if (previous_error > 0) {
      EXPECT_LT(error, previous_error / 3) << "resolution " << res;  // O(h²)
    }
    previous_error = error;
  }
  EXPECT_LT(previous_error, 0.01 * exact);
}

TEST(PrimitiveMeshes, BoxIsExactAtEveryResolution) {
  const Vec3 b(0.3, 0.05, 0.7);
  for (int res : {1, 2, 5}) {
    const PrimitiveMesh m = geometry::box_mesh(b, res);
    EXPECT_EQ(m.vertices.rows(), 6 * res * res + 2);  // Euler: V = F/2 + 2 for a closed genus-0 surface
    EXPECT_EQ(m.faces.rows(), 12 * res * res);
    expect_on_surface_and_outward(m, geometry::BoxSdf(b), 1e-15);
    expect_closed(m);
    EXPECT_NEAR(signed_volume(m), 8 * b.prod(), 1e-15);
  }
}

TEST(PrimitiveMeshes, CylinderIsThePolygonalPrism) {
  const double r = 0.12, h = 0.4;
  double previous_error = 0;
  for (int res : {6, 12, 24, 48}) {
    const PrimitiveMesh m = geometry::cylinder_mesh(r, h, res);
    expect_on_surface_and_outward(m, geometry::CylinderSdf(r, h));
    expect_closed(m);
    // Flat caps: exactly a prism over the regular res-gon inscribed in the circle.
    const double prism = 0.5 * res * r * r * std::sin(2 * kPi / res) * 2 * h;
    EXPECT_NEAR(signed_volume(m), prism, 1e-14);
    const double error = kPi * r * r * 2 * h - prism;
    if (previous_error > 0) {
      EXPECT_LT(error, previous_error / 3);
    }
    previous_error = error;
  }
}

TEST(PrimitiveMeshes, CapsuleOnItsSdfAndConverging) {
  const double r = 0.08, h = 0.25, exact = kPi * r * r * 2 * h + 4.0 / 3.0 * kPi * r * r * r;
  for (double hl : {0.0, h}) {
    const PrimitiveMesh m = geometry::capsule_mesh(r, hl, 16);
    expect_on_surface_and_outward(m, geometry::CapsuleSdf(r, hl));
    expect_closed(m);
  }
  const double v32 = signed_volume(geometry::capsule_mesh(r, h, 32));
  const double v64 = signed_volume(geometry::capsule_mesh(r, h, 64));
  EXPECT_LT(exact - v64, (exact - v32) / 3);
  EXPECT_GT(v64, 0.99 * exact);
  EXPECT_LT(v64, exact);
}

TEST(PrimitiveMeshes, PlanePatchLiesInThePlaneFacingItsNormal) {
  const Vec3 n = Vec3(0.2, 1.0, -0.3).normalized();
  const double offset = -0.45, half = 1.5;
  const Vec3 center(0.7, 3.0, -0.2);
  const PrimitiveMesh m = geometry::plane_patch_mesh(2.5 * n, offset, half, center, 3);
  ASSERT_EQ(m.vertices.rows(), 16);
  ASSERT_EQ(m.faces.rows(), 18);
  expect_on_surface_and_outward(m, geometry::PlaneSdf(n, offset), 1e-12);
  // Centred at the projection of `center`, a square of side 2·half.
  const Vec3 foot = center - (n.dot(center) - offset) * n;
  EXPECT_LT((m.vertices.colwise().mean().transpose() - foot).norm(), 1e-12);
  double area = 0;
  for (Eigen::Index f = 0; f < m.faces.rows(); ++f) {
    const Vec3 a = m.vertices.row(m.faces(f, 0)), b = m.vertices.row(m.faces(f, 1)), c = m.vertices.row(m.faces(f, 2));
    const Vec3 fn = 0.5 * (b - a).cross(c - a);
    EXPECT_NEAR(fn.normalized().dot(n), 1.0, 1e-12);
    area += fn.norm();
  }
  EXPECT_NEAR(area, 4 * half * half, 1e-12);
  // The floor: edges along −Z and −X as documented.
  const PrimitiveMesh floor = geometry::primitive_mesh(geometry::PlaneSdf(), 1.0);
  EXPECT_LT((floor.vertices.row(1) - floor.vertices.row(0) - Vec3(-2, 0, 0).transpose()).norm(), 1e-12);
  EXPECT_LT((floor.vertices.row(3) - floor.vertices.row(1) - Vec3(0, 0, -2).transpose()).norm(), 1e-12);
  EXPECT_NEAR(floor.vertices.col(1).cwiseAbs().maxCoeff(), 0.0, 0.0);
}

TEST(PrimitiveMeshes, BadSizesAndResolutionsThrow) {
  test::expect_error([] { geometry::sphere_mesh(-1.0); }, {"radius"});
  test::expect_error([] { geometry::sphere_mesh(1.0, 2); }, {"resolution", ">= 3"});
  test::expect_error([] { geometry::box_mesh(Vec3(1, 0, 1)); }, {"box", "half extent"});
  test::expect_error([] { geometry::box_mesh(Vec3(1, 1, 1), 0); }, {"resolution"});
  test::expect_error([] { geometry::cylinder_mesh(0.1, 0.0); }, {"cylinder"});
  test::expect_error([] { geometry::plane_patch_mesh(Vec3::Zero(), 0, 1); }, {"normal"});
  test::expect_error([] { geometry::plane_patch_mesh(Vec3::UnitY(), 0, 0); }, {"half size"});
}

TEST(PrimitiveMeshes, SplitSharpEdgesKeepsSmoothSurfacesAndSplitsCorners) {
  // A box corner joins three faces at 90°: 3 copies of each of its 8 corners.
  const PrimitiveMesh box = geometry::box_mesh(Vec3(1, 2, 3));
  const PrimitiveMesh split = geometry::split_sharp_edges(box.vertices, box.faces);
  EXPECT_EQ(split.vertices.rows(), 24);
  ASSERT_EQ(split.faces.rows(), box.faces.rows());
  for (Eigen::Index f = 0; f < box.faces.rows(); ++f)
    for (int k = 0; k < 3; ++k)
      EXPECT_EQ(split.vertices.row(split.faces(f, k)), box.vertices.row(box.faces(f, k)));
  // A sphere at 32 segments has no crease above 40°: nothing is split.
  const PrimitiveMesh sphere = geometry::sphere_mesh(1.0, 32);
  EXPECT_EQ(geometry::split_sharp_edges(sphere.vertices, sphere.faces).vertices.rows(), sphere.vertices.rows());
  // A cylinder splits exactly its two rims (side vs cap at 90°).
  const PrimitiveMesh cyl = geometry::cylinder_mesh(1.0, 1.0, 16);
  EXPECT_EQ(geometry::split_sharp_edges(cyl.vertices, cyl.faces).vertices.rows(), cyl.vertices.rows() + 2 * 16);
}

}  // namespace
}  // namespace sflsh
