#include "sflsh/io/surface_normals.hpp"

namespace sflsh::io {

Points vertex_normals(const Points& V, const Triangles& F) {
  Points N = Points::Zero(V.rows(), 3);
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const Vec3 a = V.row(F(f, 0)), b = V.row(F(f, 1)), c = V.row(F(f, 2));
    // The unnormalized cross product has length 2*area: area weighting for free.
    const Vec3 n = (b - a).cross(c - a);
    for (int k = 0; k < 3; ++k) N.row(F(f, k)) += n.transpose();
  }
  for (Eigen::Index v = 0; v < N.rows(); ++v) {
    const double len = N.row(v).norm();
    if (len > 0) N.row(v) /= len;
  }
  return N;
}

}  // namespace sflsh::io
