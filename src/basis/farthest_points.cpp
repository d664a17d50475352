#include "farthest_points.hpp"

#include <algorithm>

namespace sflsh::basis {

std::vector<int> farthest_points(const Points& points, int m) {
  m = std::min<int>(m, int(points.rows()));
  if (m <= 0) return {};
  const Vec3 mid = points.colwise().mean();
  VecX dist = (points.rowwise() - mid.transpose()).rowwise().squaredNorm();
  int first = 0;
  dist.minCoeff(&first);
  std::vector<int> chosen{first};
  dist = (points.rowwise() - points.row(first)).rowwise().squaredNorm();
  while (int(chosen.size()) < m) {
    int next = 0;
    dist.maxCoeff(&next);
    chosen.push_back(next);
    dist = dist.cwiseMin((points.rowwise() - points.row(next)).rowwise().squaredNorm());
  }
  return chosen;
}

}  // namespace sflsh::basis
