#include "sflsh/volume/surface_query.hpp"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <vector>

#include "sflsh/core/error.hpp"

namespace sflsh {
namespace {
using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Triangle = K::Triangle_3;
using Iterator = std::vector<Triangle>::const_iterator;
using Primitive = CGAL::AABB_triangle_primitive<K, Iterator>;
using Traits = CGAL::AABB_traits<K, Primitive>;
using Tree = CGAL::AABB_tree<Traits>;
}  // namespace

struct SurfaceQuery::Impl {
  std::vector<Triangle> triangles;
  Tree tree;
  Points V;
  Triangles F;
  // Pseudo-normals: unit face normals, angle-weighted vertex normals, and per
  // face edge i (opposite corner i... see edge_normal) the sum of the normals
  // of the two faces sharing it.
  std::vector<Vec3> face_n, vertex_n;
  std::vector<std::array<Vec3, 3>> edge_n;  // edge_n[f][i]: edge (F(f,i), F(f,i+1))
};

SurfaceQuery::SurfaceQuery(const Points& V, const Triangles& F) : impl_(std::make_unique<Impl>()) {
  require(V.rows() > 0 && F.rows() > 0, "SurfaceQuery: empty surface");
  impl_->V = V;
  impl_->F = F;
  impl_->triangles.reserve(F.rows());
  for (int f = 0; f < F.rows(); ++f) {
    auto p = [&](int i) { return K::Point_3(V(F(f, i), 0), V(F(f, i), 1), V(F(f, i), 2)); };
    impl_->triangles.emplace_back(p(0), p(1), p(2));
  }
  impl_->tree.insert(impl_->triangles.begin(), impl_->triangles.end());
  impl_->tree.build();
  impl_->tree.accelerate_distance_queries();

  const int nF = int(F.rows());
  impl_->face_n.resize(nF);
  impl_->vertex_n.assign(V.rows(), Vec3::Zero());
  impl_->edge_n.resize(nF);
  std::map<std::pair<int, int>, Vec3> edge_sum;
  for (int f = 0; f < nF; ++f) {
    const Vec3 x[3] = {V.row(F(f, 0)), V.row(F(f, 1)), V.row(F(f, 2))};
    Vec3 n = (x[1] - x[0]).cross(x[2] - x[0]);
    n = n.norm() > 0 ? Vec3(n.normalized()) : Vec3::Zero();
    impl_->face_n[f] = n;
    for (int i = 0; i < 3; ++i) {
      const Vec3 e1 = x[(i + 1) % 3] - x[i], e2 = x[(i + 2) % 3] - x[i];
      const double c = e1.norm() * e2.norm();
      const double angle = c > 0 ? std::acos(std::clamp(e1.dot(e2) / c, -1.0, 1.0)) : 0.0;
      impl_->vertex_n[F(f, i)] += angle * n;
      const int a = F(f, i), b = F(f, (i + 1) % 3);
      // Not edge_sum[key] += n: map::operator[] value-initializes a Vec3,
      // and Eigen's default constructor leaves it uninitialized. Garbage from
      // reused heap memory then flipped the sign of signed_distance() far
      // outside the skin (scripts/results/cgal_hang.md).
      edge_sum.try_emplace({std::min(a, b), std::max(a, b)}, Vec3::Zero()).first->second += n;
    }
  }
  for (int f = 0; f < nF; ++f)
    for (int i = 0; i < 3; ++i) {
      const int a = F(f, i), b = F(f, (i + 1) % 3);
      impl_->edge_n[f][i] = edge_sum.at({std::min(a, b), std::max(a, b)});
    }
}

double SurfaceQuery::signed_distance(const Vec3& x) const {
  const K::Point_3 q(x.x(), x.y(), x.z());
  const auto hit = impl_->tree.closest_point_and_primitive(q);
  const Vec3 c(hit.first.x(), hit.first.y(), hit.first.z());
  const int f = int(hit.second - impl_->triangles.begin());
  const double dist = (x - c).norm();
  // Which feature of triangle f holds c: barycentric coordinates near zero
  // mark an edge (one) or a vertex (two).
  const Vec3 a = impl_->V.row(impl_->F(f, 0)), b = impl_->V.row(impl_->F(f, 1)), d = impl_->V.row(impl_->F(f, 2));
  const Vec3 n = (b - a).cross(d - a);
  const double nn = n.squaredNorm();
  Vec3 pseudo = impl_->face_n[f];
  if (nn > 0) {
    Vec3 w;
    w[1] = (c - a).cross(d - a).dot(n) / nn;
    w[2] = (b - a).cross(c - a).dot(n) / nn;
    w[0] = 1.0 - w[1] - w[2];
    const double eps = 1e-9;
    int zeros = 0, nonzero_last = -1, zero_last = -1;
    for (int i = 0; i < 3; ++i) (w[i] < eps ? (++zeros, zero_last = i) : (nonzero_last = i));
    if (zeros == 2) {
      pseudo = impl_->vertex_n[impl_->F(f, nonzero_last)];
    } else if (zeros == 1) {
      // Zero coordinate at corner i: c lies on the edge opposite i, which is
      // edge (i+1, i+2) = edge_n[f][(i+1)%3].
      pseudo = impl_->edge_n[f][(zero_last + 1) % 3];
    }
  }
  return (x - c).dot(pseudo) < 0 ? -dist : dist;
}

SurfaceQuery::~SurfaceQuery() = default;
SurfaceQuery::SurfaceQuery(SurfaceQuery&&) noexcept = default;
SurfaceQuery& SurfaceQuery::operator=(SurfaceQuery&&) noexcept = default;

bool SurfaceQuery::inside(const Vec3& x) const {
  // Ray parity with a fixed, "generic" direction, as CGAL::Side_of_triangle_mesh
  // does; on a degenerate hit (edge/vertex) retry with other directions and
  // take the majority, which keeps the answer deterministic.
  static const K::Vector_3 dirs[3] = {K::Vector_3(0.4127, 0.8173, 0.2219), K::Vector_3(-0.6311, 0.2983, 0.7161),
                                      K::Vector_3(0.1731, -0.5383, 0.8249)};
  const K::Point_3 p(x.x(), x.y(), x.z());
  auto odd = [&](int i) { return impl_->tree.number_of_intersected_primitives(K::Ray_3(p, dirs[i])) % 2 == 1; };
  const bool a = odd(0), b = odd(1);
  return a == b ? a : odd(2);
}

double SurfaceQuery::distance(const Vec3& x) const {
  return std::sqrt(CGAL::to_double(impl_->tree.squared_distance(K::Point_3(x.x(), x.y(), x.z()))));
}

Vec3 SurfaceQuery::closest_point(const Vec3& x, int* face, Vec3* bary) const {
  const auto hit = impl_->tree.closest_point_and_primitive(K::Point_3(x.x(), x.y(), x.z()));
  const Vec3 c(hit.first.x(), hit.first.y(), hit.first.z());
  const int f = int(hit.second - impl_->triangles.begin());
  if (face) *face = f;
  if (bary) {
    // Barycentric coordinates of c in triangle f (c lies in it).
    const Vec3 a = impl_->V.row(impl_->F(f, 0)), b = impl_->V.row(impl_->F(f, 1)), d = impl_->V.row(impl_->F(f, 2));
    const Vec3 n = (b - a).cross(d - a);
    const double nn = n.squaredNorm();
    Vec3 w(1.0 / 3, 1.0 / 3, 1.0 / 3);
    if (nn > 0) {
      w[1] = (c - a).cross(d - a).dot(n) / nn;
      w[2] = (b - a).cross(c - a).dot(n) / nn;
      w[0] = 1.0 - w[1] - w[2];
      w = w.cwiseMax(0.0);
      w /= w.sum();
    }
    *bary = w;
  }
  return c;
}

}  // namespace sflsh
