// Surface checks on hand-made meshes whose answers are known.
#include "sflsh/meshing/surface_checks.hpp"

#include <gtest/gtest.h>

#include "sflsh/core/error.hpp"

namespace sflsh {
namespace {

struct Mesh {
  Points V;
  Triangles F;
};

/// Axis-aligned box [lo, hi], faces counter-clockwise seen from outside.
Mesh box(const Vec3& lo, const Vec3& hi) {
  Mesh m;
  m.V.resize(8, 3);
  for (int i = 0; i < 8; ++i)
    m.V.row(i) << ((i & 1) ? hi.x() : lo.x()), ((i & 2) ? hi.y() : lo.y()), ((i & 4) ? hi.z() : lo.z());
  m.F.resize(12, 3);
  m.F << 0, 2, 3, 0, 3, 1,  // z = lo (normal -z)
      4, 5, 7, 4, 7, 6,     // z = hi
      0, 1, 5, 0, 5, 4,     // y = lo
      2, 6, 7, 2, 7, 3,     // y = hi
      0, 4, 6, 0, 6, 2,     // x = lo
      1, 3, 7, 1, 7, 5;     // x = hi
  return m;
}

Mesh concatenate(const Mesh& a, const Mesh& b) {
  Mesh m;
  m.V.resize(a.V.rows() + b.V.rows(), 3);
  m.V << a.V, b.V;
  m.F.resize(a.F.rows() + b.F.rows(), 3);
  m.F << a.F, (b.F.array() + int(a.V.rows())).matrix();
  return m;
}

TEST(SurfaceChecks, UnitCubeIsAClosedGenusZeroSurface) {
  const Mesh cube = box(Vec3(0, 0, 0), Vec3(1, 2, 3));
  const SurfaceReport r = check_surface(cube.V, cube.F);
  EXPECT_EQ(r.num_vertices, 8);
  EXPECT_EQ(r.num_faces, 12);
  EXPECT_EQ(r.num_edges, 18);
  EXPECT_TRUE(r.is_closed);
  EXPECT_TRUE(r.is_manifold);
  EXPECT_TRUE(r.consistently_oriented);
  EXPECT_EQ(r.num_components, 1);
  EXPECT_EQ(r.euler_characteristic, 2);
  EXPECT_EQ(r.genus, 0);
  EXPECT_NEAR(r.signed_volume, 6.0, 1e-12);
  EXPECT_NEAR(r.area, 2 * (2 + 3 + 6), 1e-12);
  EXPECT_TRUE(r.self_intersection_tested);
  EXPECT_FALSE(r.self_intersects);
  EXPECT_NEAR(r.height(), 2.0, 1e-12);
  EXPECT_NEAR(r.min_edge_length, 1.0, 1e-12);
  EXPECT_TRUE(r.is_valid_body_surface());
  EXPECT_NE(r.describe().find("closed, manifold, oriented, 1 component, genus 0"), std::string::npos)
      << r.describe();
}

TEST(SurfaceChecks, TetrahedronVolumeAndReversedOrientation) {
  Points V(4, 3);
  V << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1;
  Triangles F(4, 3);
  F << 0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3;
  SurfaceReport r = check_surface(V, F);
  EXPECT_TRUE(r.is_closed && r.is_manifold && r.consistently_oriented);
  EXPECT_NEAR(r.signed_volume, 1.0 / 6.0, 1e-12);
  EXPECT_EQ(r.genus, 0);
  // All faces reversed: still consistent, but inside out.
  Triangles Fr = F;
  Fr.col(1).swap(Fr.col(2));
  r = check_surface(V, Fr);
  EXPECT_TRUE(r.consistently_oriented);
  EXPECT_NEAR(r.signed_volume, -1.0 / 6.0, 1e-12);
  EXPECT_FALSE(r.is_valid_body_surface());
}

TEST(SurfaceChecks, CubeWithAFaceRemovedIsOpen) {
  Mesh cube = box(Vec3(0, 0, 0), Vec3(1, 1, 1));
  Triangles F = cube.F.topRows(11);
  const SurfaceReport r = check_surface(cube.V, F);
  EXPECT_FALSE(r.is_closed);
  EXPECT_EQ(r.num_boundary_edges, 3);
  EXPECT_TRUE(r.is_manifold);  // a disc with a boundary is still a manifold
  EXPECT_EQ(r.genus, -1);
  EXPECT_FALSE(r.is_valid_body_surface());
}

TEST(SurfaceChecks, FlippedFaceIsInconsistentlyOriented) {
  Mesh cube = box(Vec3(0, 0, 0), Vec3(1, 1, 1));
  std::swap(cube.F(5, 1), cube.F(5, 2));
  const SurfaceReport r = check_surface(cube.V, cube.F);
  EXPECT_TRUE(r.is_closed);
  EXPECT_FALSE(r.consistently_oriented);
  EXPECT_EQ(r.num_misoriented_edges, 3);
  EXPECT_FALSE(r.self_intersection_tested);  // needs an oriented manifold
  EXPECT_FALSE(r.is_valid_body_surface());
}

TEST(SurfaceChecks, OverlappingBoxesSelfIntersect) {
  const Mesh m = concatenate(box(Vec3(0, 0, 0), Vec3(1, 1, 1)), box(Vec3(0.5, 0.5, 0.5), Vec3(1.5, 1.5, 1.5)));
  const SurfaceReport r = check_surface(m.V, m.F);
  EXPECT_TRUE(r.is_closed && r.is_manifold && r.consistently_oriented);
  EXPECT_EQ(r.num_components, 2);
  EXPECT_EQ(r.genus, 0);
  ASSERT_TRUE(r.self_intersection_tested);
  EXPECT_TRUE(r.self_intersects);
  // Apart, the same two boxes do not intersect.
  const Mesh apart = concatenate(box(Vec3(0, 0, 0), Vec3(1, 1, 1)), box(Vec3(2, 0, 0), Vec3(3, 1, 1)));
  const SurfaceReport ra = check_surface(apart.V, apart.F);
  EXPECT_FALSE(ra.self_intersects);
  EXPECT_FALSE(ra.is_valid_body_surface());  // two components
}

TEST(SurfaceChecks, NonManifoldEdgeAndVertex) {
  // Three triangles sharing edge (0,1): non-manifold edge.
  Points V(5, 3);
  V << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1;
  Triangles F(3, 3);
  F << 0, 1, 2, 1, 0, 3, 0, 1, 4;
  SurfaceReport r = check_surface(V, F);
  EXPECT_EQ(r.num_nonmanifold_edges, 1);
  EXPECT_FALSE(r.is_manifold);
  // Two tetrahedra touching at one vertex: closed, edge-manifold, not vertex-manifold.
  Points W(7, 3);
  W << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, -1, 0, 0, 0, -1, 0, 0, 0, -1;
  Triangles G(8, 3);
  G << 0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3,  //
      0, 5, 4, 0, 4, 6, 0, 6, 5, 4, 5, 6;
  r = check_surface(W, G);
  EXPECT_TRUE(r.is_closed);
  EXPECT_EQ(r.num_nonmanifold_vertices, 1);
  EXPECT_FALSE(r.is_manifold);
}

TEST(SurfaceChecks, WindingNumberInsideAndOutside) {
  const Mesh cube = box(Vec3(0, 0, 0), Vec3(1, 1, 1));
  EXPECT_NEAR(winding_number(cube.V, cube.F, Vec3(0.3, 0.6, 0.5)), 1.0, 1e-9);
  EXPECT_NEAR(winding_number(cube.V, cube.F, Vec3(1.3, 0.6, 0.5)), 0.0, 1e-9);
}

TEST(SurfaceChecks, BadIndexThrows) {
  const Mesh cube = box(Vec3(0, 0, 0), Vec3(1, 1, 1));
  Triangles F = cube.F;
  F(3, 2) = 8;
  EXPECT_THROW(check_surface(cube.V, F), Error);
}

}  // namespace
}  // namespace sflsh
