#include "sflsh/volume/point_embedding.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "sflsh/core/error.hpp"

namespace sflsh {
namespace {

Eigen::Vector4d barycentric(const TetMesh& m, int t, const Vec3& p) {
  const Vec3 x0 = m.nodes.row(m.elements(t, 0));
  Mat3 D;
  for (int i = 0; i < 3; ++i) D.col(i) = m.nodes.row(m.elements(t, i + 1)).transpose() - x0;
  const Vec3 l = D.lu().solve(p - x0);
  return Eigen::Vector4d(1.0 - l.sum(), l[0], l[1], l[2]);
}

}  // namespace

PointEmbedding embed_points(const TetMesh& m, const Points& P) {
  const int T = m.num_elements();
  require(T > 0, "embed_points: empty tet mesh");
  // Uniform grid of tet bounding boxes, cell ~ 2 mean tet extents.
  const Vec3 lo = m.nodes.colwise().minCoeff().transpose(), hi = m.nodes.colwise().maxCoeff().transpose();
  double ext = 0;
  for (int t = 0; t < T; ++t) {
    Vec3 a = m.nodes.row(m.elements(t, 0)), b = a;
    for (int i = 1; i < 4; ++i) a = a.cwiseMin(m.nodes.row(m.elements(t, i)).transpose()), b = b.cwiseMax(m.nodes.row(m.elements(t, i)).transpose());
    ext += (b - a).maxCoeff();
  }
  const double h = std::max(2.0 * ext / T, 1e-6);
  const Eigen::Vector3i dims = (((hi - lo) / h).array().floor().cast<int>() + 1).matrix();
  auto cell_of = [&](const Vec3& x) -> Eigen::Vector3i {
    Eigen::Vector3i c = ((x - lo) / h).array().floor().cast<int>().matrix();
    return c.cwiseMax(0).cwiseMin(dims - Eigen::Vector3i::Ones());
  };
  auto key = [&](const Eigen::Vector3i& c) { return (size_t(c.z()) * dims.y() + c.y()) * dims.x() + c.x(); };
  std::vector<std::vector<int>> grid(size_t(dims.x()) * dims.y() * dims.z());
  for (int t = 0; t < T; ++t) {
    Vec3 a = m.nodes.row(m.elements(t, 0)), b = a;
    for (int i = 1; i < 4; ++i) a = a.cwiseMin(m.nodes.row(m.elements(t, i)).transpose()), b = b.cwiseMax(m.nodes.row(m.elements(t, i)).transpose());
    const Eigen::Vector3i ca = cell_of(a), cb = cell_of(b);
    for (int z = ca.z(); z <= cb.z(); ++z)
      for (int y = ca.y(); y <= cb.y(); ++y)
        for (int x = ca.x(); x <= cb.x(); ++x) grid[key({x, y, z})].push_back(t);
  }

  PointEmbedding e;
  const int nP = int(P.rows());
  e.tet.resize(nP);
  e.bary.resize(nP, 4);
  e.distance.resize(nP);
  for (int p = 0; p < nP; ++p) {
    const Vec3 x = P.row(p);
    const Eigen::Vector3i c = cell_of(x);
    double best = std::numeric_limits<double>::infinity();
    int best_t = -1;
    Eigen::Vector4d best_b;
    // Ring 0 (own cell) holds the containing tet if there is one; outside
    // points look a few rings further for the nearest tet.
    for (int ring = 0; ring <= 3 && best > 0; ++ring) {
      for (int z = c.z() - ring; z <= c.z() + ring; ++z)
        for (int y = c.y() - ring; y <= c.y() + ring; ++y)
          for (int xx = c.x() - ring; xx <= c.x() + ring; ++xx) {
            if (std::max({std::abs(z - c.z()), std::abs(y - c.y()), std::abs(xx - c.x())}) != ring) continue;
            if (xx < 0 || y < 0 || z < 0 || xx >= dims.x() || y >= dims.y() || z >= dims.z()) continue;
            for (int t : grid[key({xx, y, z})]) {
              Eigen::Vector4d b = barycentric(m, t, x);
              double dist = 0;
              if (b.minCoeff() < 0) {
                b = b.cwiseMax(0.0);
                b /= b.sum();
                Vec3 y3 = Vec3::Zero();
                for (int i = 0; i < 4; ++i) y3 += b[i] * m.nodes.row(m.elements(t, i)).transpose();
                dist = (y3 - x).norm();
              }
              if (dist < best) best = dist, best_t = t, best_b = b;
            }
          }
      if (best_t >= 0 && ring >= 1) break;  // nearest found within the first ring around
    }
    require(best_t >= 0, "embed_points: point ", p, " is farther than 3 grid cells from every tet");
    e.tet[p] = best_t;
    e.bary.row(p) = best_b.transpose();
    e.distance[p] = best;
    e.num_outside += best > 0;
  }
  return e;
}

}  // namespace sflsh
