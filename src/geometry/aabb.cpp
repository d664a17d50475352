#include "sflsh/geometry/aabb.hpp"

namespace sflsh::geometry {

Aabb Aabb::unbounded() {
  const double inf = std::numeric_limits<double>::infinity();
  return Aabb(Vec3::Constant(-inf), Vec3::Constant(inf));
}

Aabb Aabb::of_points(const Points& x) {
  Aabb b;
  if (x.rows() == 0) return b;
  b.min = x.colwise().minCoeff().transpose();
  b.max = x.colwise().maxCoeff().transpose();
  return b;
}

void Aabb::extend(const Vec3& p) {
  min = min.cwiseMin(p);
  max = max.cwiseMax(p);
}

void Aabb::extend(const Aabb& b) {
  if (b.empty()) return;
  min = min.cwiseMin(b.min);
  max = max.cwiseMax(b.max);
}

Aabb Aabb::inflated(double margin) const {
  if (empty()) return *this;
  return Aabb(min.array() - margin, max.array() + margin);
}

bool Aabb::contains(const Vec3& p) const { return (p.array() >= min.array()).all() && (p.array() <= max.array()).all(); }

bool Aabb::intersects(const Aabb& b) const {
  if (empty() || b.empty()) return false;
  return (min.array() <= b.max.array()).all() && (b.min.array() <= max.array()).all();
}

Aabb Aabb::transformed(const Eigen::Isometry3d& pose) const {
  if (empty()) return *this;
  if (is_unbounded()) return unbounded();
  Aabb out;
  for (int c = 0; c < 8; ++c) {
    const Vec3 corner((c & 1) ? max.x() : min.x(), (c & 2) ? max.y() : min.y(), (c & 4) ? max.z() : min.z());
    out.extend(Vec3(pose * corner));
  }
  return out;
}

}  // namespace sflsh::geometry
