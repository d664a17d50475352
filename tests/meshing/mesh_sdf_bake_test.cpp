// Mesh SDF baking against exact CGAL distances (a separate AABB tree over
// the triangles, sign from the generalized winding number), the closedness
// check, and the disk cache.
#include "sflsh/meshing/mesh_sdf_bake.hpp"

#include <gtest/gtest.h>

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <filesystem>
#include <map>
#include <random>

#include "sflsh/io/mesh_export.hpp"
#include "sflsh/meshing/surface_checks.hpp"
#include "test_support.hpp"

namespace sflsh {
namespace {

struct Mesh {
  Points V;
  Triangles F;
};

/// Icosahedron subdivided `levels` times, projected to the sphere of radius r
/// around c (faces counter-clockwise from outside).
Mesh icosphere(double r, const Vec3& c, int levels) {
  const double t = (1 + std::sqrt(5.0)) / 2;
  std::vector<Vec3> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                         {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  std::vector<Eigen::Vector3i> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                                    {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                                    {3, 8, 9},  {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (auto& p : v) p.normalize();
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back((v[a] + v[b]).normalized());
      return mid[key] = int(v.size()) - 1;
    };
    std::vector<Eigen::Vector3i> g;
    for (const auto& tri : f) {
      const int a = midpoint(tri[0], tri[1]), b = midpoint(tri[1], tri[2]), d = midpoint(tri[2], tri[0]);
      g.push_back({tri[0], a, d});
      g.push_back({tri[1], b, a});
      g.push_back({tri[2], d, b});
      g.push_back({a, b, d});
    }
    f = g;
  }
  Mesh m;
  m.V.resize(Eigen::Index(v.size()), 3);
  for (std::size_t i = 0; i < v.size(); ++i) m.V.row(Eigen::Index(i)) = (c + r * v[i]).transpose();
  m.F.resize(Eigen::Index(f.size()), 3);
  for (std::size_t i = 0; i < f.size(); ++i) m.F.row(Eigen::Index(i)) = f[i].transpose();
  return m;
}

/// Exact signed distance to (V, F): CGAL AABB tree over a triangle soup for
/// the distance, generalized winding number for the sign.
class ExactDistance {
 public:
  using K = CGAL::Exact_predicates_inexact_constructions_kernel;
  using Tree = CGAL::AABB_tree<CGAL::AABB_traits<K, CGAL::AABB_triangle_primitive<K, std::vector<K::Triangle_3>::const_iterator>>>;
  explicit ExactDistance(const Mesh& m) : m_(m) {
    auto p = [&](int v) { return K::Point_3(m.V(v, 0), m.V(v, 1), m.V(v, 2)); };
    for (int f = 0; f < m.F.rows(); ++f) tris_.emplace_back(p(m.F(f, 0)), p(m.F(f, 1)), p(m.F(f, 2)));
    tree_.insert(tris_.begin(), tris_.end());
    tree_.build();
  }
  double operator()(const Vec3& x) const {
    const double d = std::sqrt(tree_.squared_distance(K::Point_3(x.x(), x.y(), x.z())));
    return winding_number(m_.V, m_.F, x) > 0.5 ? -d : d;
  }

 private:
  Mesh m_;
  std::vector<K::Triangle_3> tris_;
  Tree tree_;
};

TEST(MeshSdfBake, MatchesExactCgalDistanceWithinHalfAVoxelInTheBand) {
  const Mesh m = icosphere(0.1, Vec3(0.02, -0.03, 0.01), 2);  // 320 faces
  MeshSdfBakeOptions o;
  o.voxel_size = 0.01;
  o.padding = 0.03;
  o.band = 0.025;
  MeshSdfBakeReport rep;
  const geometry::GridSdf g = bake_mesh_sdf(m.V, m.F, o, "icosphere", &rep);
  EXPECT_GT(rep.estimated_nodes, 0);  // the narrow band skipped far blocks
  EXPECT_LT(rep.exact_nodes, long(g.values().size()));  // fewer queries than nodes
  const ExactDistance exact(m);
  // Nodes in the band are exact.
  for (int k = 0; k < g.dims().z(); ++k)
    for (int j = 0; j < g.dims().y(); ++j)
      for (int i = 0; i < g.dims().x(); ++i) {
        const double e = exact(g.node_position(i, j, k));
        if (std::abs(e) < o.band) {
          EXPECT_NEAR(g.node_value(i, j, k), e, 1e-12);
        }
      }
  // Interpolated values within half a voxel, at random points of the band.
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-0.13, 0.13);
  int checked = 0;
  double worst = 0;
  while (checked < 400) {
    const Vec3 x = Vec3(0.02, -0.03, 0.01) + Vec3(u(rng), u(rng), u(rng));
    const double e = exact(x);
    if (std::abs(e) > o.band - o.voxel_size) continue;
    worst = std::max(worst, std::abs(g.distance(x) - e));
    ++checked;
  }
  EXPECT_LT(worst, 0.5 * o.voxel_size);
  // A grid point deep inside is negative, far outside positive (the estimate keeps the sign).
  EXPECT_LT(g.distance(Vec3(0.02, -0.03, 0.01)), -0.09);
  EXPECT_GT(g.distance(Vec3(0.14, 0.09, 0.13)), 0.05);
}

TEST(MeshSdfBake, FullGridEqualsExactDistanceAtEveryNode) {
  const Mesh m = icosphere(0.05, Vec3::Zero(), 1);
  MeshSdfBakeOptions o;
  o.voxel_size = 0.01;
  o.padding = 0.01;
  MeshSdfBakeReport rep;
  const geometry::GridSdf g = bake_mesh_sdf(m.V, m.F, o, "icosphere", &rep);
  EXPECT_EQ(rep.estimated_nodes, 0);
  const ExactDistance exact(m);
  for (int k = 0; k < g.dims().z(); ++k)
    for (int j = 0; j < g.dims().y(); ++j)
      for (int i = 0; i < g.dims().x(); ++i) EXPECT_NEAR(g.node_value(i, j, k), exact(g.node_position(i, j, k)), 1e-12);
  EXPECT_TRUE(g.bounds().contains(Vec3::Constant(0.059)));
}

TEST(MeshSdfBake, RejectsAnOpenMeshAndBadOptions) {
  Mesh m = icosphere(0.05, Vec3::Zero(), 1);
  Mesh open = m;
  open.F.conservativeResize(m.F.rows() - 1, 3);  // a hole
  test::expect_error([&] { bake_mesh_sdf(open.V, open.F, {}, "cup.obj"); }, {"cup.obj", "closed", "3 boundary edges"});
  MeshSdfBakeOptions o;
  o.voxel_size = -1;
  test::expect_error([&] { bake_mesh_sdf(m.V, m.F, o, "ball.obj"); }, {"ball.obj", "voxel size"});
  o.voxel_size = 1e-5;
  test::expect_error([&] { bake_mesh_sdf(m.V, m.F, o, "ball.obj"); }, {"ball.obj", "nodes", "larger voxel size"});
}

TEST(MeshSdfBake, FileCacheIsKeyedByMeshAndOptions) {
  test::TempDir dir;
  const Mesh m = icosphere(50.0, Vec3::Zero(), 1);  // millimetres
  io::write_mesh(dir.file("ball.obj"), m.V, m.F);
  MeshSdfBakeOptions o;
  o.voxel_size = 0.01;
  o.padding = 0.01;
  MeshSdfBakeReport first, second, other;
  const auto g1 = load_or_bake_mesh_sdf(dir.file("ball.obj"), 0.001, o, dir.file("cache"), &first);
  EXPECT_FALSE(first.cache_hit);
  EXPECT_TRUE(std::filesystem::exists(first.cache_path));
  const auto g2 = load_or_bake_mesh_sdf(dir.file("ball.obj"), 0.001, o, dir.file("cache"), &second);
  EXPECT_TRUE(second.cache_hit) << second.describe();
  EXPECT_EQ(second.cache_path, first.cache_path);
  EXPECT_EQ(g1.values(), g2.values());
  // Scaled to metres (a 5 cm ball): the exact distance of the scaled mesh.
  const ExactDistance exact_m({m.V * 0.001, m.F});
  for (const Vec3& x : {Vec3(0, 0, 0), Vec3(0.03, 0.02, -0.01), Vec3(0.055, 0.0, 0.0)})
    EXPECT_NEAR(g1.distance(x), exact_m(x), 0.5 * o.voxel_size);
  o.voxel_size = 0.012;
  load_or_bake_mesh_sdf(dir.file("ball.obj"), 0.001, o, dir.file("cache"), &other);
  EXPECT_FALSE(other.cache_hit);
  EXPECT_NE(other.cache_path, first.cache_path);
  // A damaged cache file is baked again.
  std::filesystem::resize_file(first.cache_path, 100);
  MeshSdfBakeReport again;
  o.voxel_size = 0.01;
  const auto g3 = load_or_bake_mesh_sdf(dir.file("ball.obj"), 0.001, o, dir.file("cache"), &again);
  EXPECT_FALSE(again.cache_hit);
  EXPECT_EQ(g3.values(), g1.values());
  // Unreadable and open meshes name the file.
  test::expect_error([&] { load_or_bake_mesh_sdf(dir.file("none.stl"), 1.0, o, ""); }, {"none.stl"});
  Mesh open = m;
  open.F.conservativeResize(m.F.rows() - 2, 3);
  io::write_mesh(dir.file("open.ply"), open.V, open.F);
  test::expect_error([&] { load_or_bake_mesh_sdf(dir.file("open.ply"), 1.0, o, dir.file("cache")); }, {"open.ply", "closed"});
}

}  // namespace
}  // namespace sflsh
