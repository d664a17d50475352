#include "sflsh/geometry/point_grid.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "sflsh/core/error.hpp"

namespace sflsh::geometry {

PointGrid::PointGrid(const Points& points, double cell_size) : points_(points), cell_(cell_size) {
  require(std::isfinite(cell_size) && cell_size > 0, "PointGrid: cell size must be finite and > 0, got ", cell_size);
  require(points.allFinite(), "PointGrid: points must be finite");
  const int n = int(points.rows());
  if (n == 0) return;
  std::vector<Key> keys(n);
  lo_ = cell_of(points.row(0).transpose());
  hi_ = lo_;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3i c = cell_of(points.row(i).transpose());
    lo_ = lo_.cwiseMin(c);
    hi_ = hi_.cwiseMax(c);
    keys[i] = key(c);
  }
  require(((hi_ - lo_).array() < (1 << 21)).all(), "PointGrid: the points span more than 2^21 cells of ", cell_size,
          " m along an axis; use a larger cell size");
  order_.resize(n);
  std::iota(order_.begin(), order_.end(), 0);
  std::stable_sort(order_.begin(), order_.end(), [&](int a, int b) { return keys[a] < keys[b]; });
  for (int b = 0; b < n;) {
    int e = b + 1;
    while (e < n && keys[order_[e]] == keys[order_[b]]) ++e;
    cells_.emplace(keys[order_[b]], std::make_pair(b, e));
    b = e;
  }
}

Eigen::Vector3i PointGrid::cell_of(const Vec3& p) const {
  return Eigen::Vector3i(int(std::floor(p.x() / cell_)), int(std::floor(p.y() / cell_)), int(std::floor(p.z() / cell_)));
}

PointGrid::Key PointGrid::key(const Eigen::Vector3i& c) {
  // 21 bits per axis (offset to unsigned): cells of 1 mm cover ±1 km.
  const auto u = [](int v) { return Key(std::uint32_t(v + (1 << 20)) & 0x1fffff); };
  return u(c.x()) | (u(c.y()) << 21) | (u(c.z()) << 42);
}

void PointGrid::query(const Aabb& box, std::vector<int>& out) const {
  out.clear();
  if (box.empty() || points_.rows() == 0) return;
  auto take = [&](const std::pair<int, int>& range) {
    for (int k = range.first; k < range.second; ++k)
      if (box.contains(points_.row(order_[k]).transpose())) out.push_back(order_[k]);
  };
  // The box's cell range clipped to the occupied range (unbounded boxes included).
  Eigen::Vector3i a = lo_, b = hi_;
  for (int ax = 0; ax < 3; ++ax) {
    if (std::isfinite(box.min[ax])) a[ax] = int(std::max<double>(lo_[ax], std::floor(box.min[ax] / cell_)));
    if (std::isfinite(box.max[ax])) b[ax] = int(std::min<double>(hi_[ax], std::floor(box.max[ax] / cell_)));
  }
  if ((a.array() > b.array()).any()) return;
  const double visits = double(b.x() - a.x() + 1) * double(b.y() - a.y() + 1) * double(b.z() - a.z() + 1);
  if (visits > double(cells_.size())) {
    for (const auto& [k, range] : cells_) take(range);
  } else {
    for (int z = a.z(); z <= b.z(); ++z)
      for (int y = a.y(); y <= b.y(); ++y)
        for (int x = a.x(); x <= b.x(); ++x) {
          const auto it = cells_.find(key(Eigen::Vector3i(x, y, z)));
          if (it != cells_.end()) take(it->second);
        }
  }
  std::sort(out.begin(), out.end());
}

int PointGrid::nearest(const Vec3& x, double max_distance, double* distance) const {
  double best = max_distance;
  int found = -1;
  if (points_.rows() > 0 && max_distance >= 0) {
    const Eigen::Vector3i c = cell_of(x);
    // Cells of ring k lie at least (k − 1) cells from x (x anywhere in its cell).
    const int rings = int(std::ceil(max_distance / cell_)) + 1;
    for (int k = 0; k <= rings; ++k) {
      if (found >= 0 && best <= (k - 1) * cell_) break;
      const Eigen::Vector3i a = (c.array() - k).max(lo_.array()), b = (c.array() + k).min(hi_.array());
      for (int z = a.z(); z <= b.z(); ++z)
        for (int y = a.y(); y <= b.y(); ++y) {
          // Inside the ring's cube only its shell: every x on the z and y
          // faces, else the two x faces.
          const bool face = std::abs(z - c.z()) == k || std::abs(y - c.y()) == k;
          const int step = face || k == 0 ? 1 : 2 * k;
          for (int xx = face ? a.x() : c.x() - k; xx <= b.x(); xx += step) {
            if (xx < a.x()) continue;
            const auto it = cells_.find(key(Eigen::Vector3i(xx, y, z)));
            if (it == cells_.end()) continue;
            for (int i = it->second.first; i < it->second.second; ++i) {
              const double dist = (points_.row(order_[i]).transpose() - x).norm();
              if (dist <= best && (found < 0 || dist < best || order_[i] < found)) {
                best = dist;
                found = order_[i];
              }
            }
          }
        }
    }
  }
  if (distance) *distance = found >= 0 ? best : std::numeric_limits<double>::infinity();
  return found;
}

bool PointGrid::occupied(const Aabb& box) const {
  if (box.empty() || points_.rows() == 0) return false;
  Eigen::Vector3i a = lo_, b = hi_;
  for (int ax = 0; ax < 3; ++ax) {
    if (std::isfinite(box.min[ax])) a[ax] = int(std::max<double>(lo_[ax], std::floor(box.min[ax] / cell_)));
    if (std::isfinite(box.max[ax])) b[ax] = int(std::min<double>(hi_[ax], std::floor(box.max[ax] / cell_)));
  }
  if ((a.array() > b.array()).any()) return false;
  for (int z = a.z(); z <= b.z(); ++z)
    for (int y = a.y(); y <= b.y(); ++y)
      for (int x = a.x(); x <= b.x(); ++x)
        if (cells_.count(key(Eigen::Vector3i(x, y, z)))) return true;
  return false;
}

std::vector<int> PointGrid::query(const Aabb& box) const {
  std::vector<int> out;
  query(box, out);
  return out;
}

}  // namespace sflsh::geometry
