#include "sflsh/sim/proximity_sensor.hpp"

#include <algorithm>
#include <cmath>

#include "sflsh/core/error.hpp"

namespace sflsh {
namespace {

constexpr int kLeafSize = 4;

/// Entry parameter of the ray into `box` if it crosses it within [0, t_max], else +inf.
double slab_entry(const geometry::Aabb& box, const Vec3& o, const Vec3& d, double t_max) {
  double lo = 0, hi = t_max;
  for (int i = 0; i < 3; ++i) {
    if (std::abs(d[i]) < 1e-300) {
      if (o[i] < box.min[i] || o[i] > box.max[i]) return INFINITY;
      continue;
    }
    double t1 = (box.min[i] - o[i]) / d[i], t2 = (box.max[i] - o[i]) / d[i];
    if (t1 > t2) std::swap(t1, t2);
    lo = std::max(lo, t1), hi = std::min(hi, t2);
    if (lo > hi) return INFINITY;
  }
  return lo;
}

}  // namespace

bool ray_triangle(const Vec3& origin, const Vec3& direction, const Vec3& a, const Vec3& b, const Vec3& c, double& t,
                  double& u, double& v) {
  const Vec3 e1 = b - a, e2 = c - a;
  const Vec3 p = direction.cross(e2);
  const double det = e1.dot(p);
  if (std::abs(det) < 1e-18 * e1.norm() * e2.norm() * direction.norm() || det == 0) return false;
  const double inv = 1.0 / det;
  const Vec3 s = origin - a;
  u = s.dot(p) * inv;
  if (u < 0 || u > 1) return false;
  const Vec3 qv = s.cross(e1);
  v = direction.dot(qv) * inv;
  if (v < 0 || u + v > 1) return false;
  t = e2.dot(qv) * inv;
  return true;
}

TriangleRaycaster::TriangleRaycaster(const Points& vertices, const Triangles& faces)
    : vertices_(vertices), faces_(faces) {
  require(vertices_.allFinite(), "ray caster: vertices are not finite");
  require(faces_.size() == 0 || (faces_.minCoeff() >= 0 && faces_.maxCoeff() < vertices_.rows()),
          "ray caster: face indices out of range [0, ", vertices_.rows(), ")");
  const int F = int(faces_.rows());
  order_.resize(F);
  std::vector<Vec3> centroids(F);
  for (int f = 0; f < F; ++f) {
    order_[f] = f;
    centroids[f] = (vertices_.row(faces_(f, 0)) + vertices_.row(faces_(f, 1)) + vertices_.row(faces_(f, 2))).transpose() / 3.0;
  }
  nodes_.reserve(F > 0 ? 2 * F / kLeafSize + 2 : 1);
  if (F > 0) build(0, F, centroids);
}

int TriangleRaycaster::build(int begin, int end, const std::vector<Vec3>& centroids) {
  const int id = int(nodes_.size());
  nodes_.emplace_back();
  geometry::Aabb box, cbox;
  for (int i = begin; i < end; ++i) {
    for (int c = 0; c < 3; ++c) box.extend(Vec3(vertices_.row(faces_(order_[i], c)).transpose()));
    cbox.extend(centroids[order_[i]]);
  }
  nodes_[id].box = box;
  if (end - begin <= kLeafSize) {
    nodes_[id].begin = begin, nodes_[id].end = end;
    return id;
  }
  int axis = 0;
  (cbox.max - cbox.min).maxCoeff(&axis);
  const int mid = (begin + end) / 2;
  std::nth_element(order_.begin() + begin, order_.begin() + mid, order_.begin() + end,
                   [&](int a, int b) { return centroids[a][axis] < centroids[b][axis]; });
  const int left = build(begin, mid, centroids);
  const int right = build(mid, end, centroids);
  nodes_[id].left = left, nodes_[id].right = right;
  return id;
}

RayHit TriangleRaycaster::cast(const Vec3& origin, const Vec3& direction, double range) const {
  require(direction.allFinite() && direction.norm() > 0 && origin.allFinite(),
          "ray caster: the ray needs a finite origin and a non-zero direction");
  require(range >= 0, "ray caster: range ", range, " m, expected >= 0");
  const Vec3 d = direction.normalized();
  RayHit best;
  double t_best = range;
  tests_ = 0;
  if (nodes_.empty()) return best;
  std::vector<int> stack{0};
  while (!stack.empty()) {
    const Node& n = nodes_[stack.back()];
    stack.pop_back();
    if (!(slab_entry(n.box, origin, d, t_best) <= t_best)) continue;
    if (n.left < 0) {
      for (int i = n.begin; i < n.end; ++i) {
        const int f = order_[i];
        double t, u, v;
        ++tests_;
        if (!ray_triangle(origin, d, vertices_.row(faces_(f, 0)).transpose(), vertices_.row(faces_(f, 1)).transpose(),
                          vertices_.row(faces_(f, 2)).transpose(), t, u, v))
          continue;
        if (t < 0 || t > t_best || (best.hit && t == t_best && f > best.face)) continue;
        best.hit = true, best.face = f, best.distance = t_best = t;
        best.bary = Vec3(1 - u - v, u, v);
        best.point = origin + t * d;
      }
      continue;
    }
    // Visit the nearer child first (pushed last).
    const double tl = slab_entry(nodes_[n.left].box, origin, d, t_best);
    const double tr = slab_entry(nodes_[n.right].box, origin, d, t_best);
    if (tl <= tr) {
      stack.push_back(n.right), stack.push_back(n.left);
    } else {
      stack.push_back(n.left), stack.push_back(n.right);
    }
  }
  return best;
}

RayHit sense(const ProximitySensor& sensor, const Isometry& tool_pose, const TriangleRaycaster& skin) {
  return skin.cast(tool_pose * sensor.origin, tool_pose.linear() * sensor.direction, sensor.range);
}

}  // namespace sflsh
