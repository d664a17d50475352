#include "sflsh/sim/skin_face_samples.hpp"

#include <algorithm>
#include <cmath>

#include "sflsh/core/error.hpp"

namespace sflsh {

int face_subdivisions(const Points& rest, const Triangles& faces, int f, double spacing) {
  const Vec3 a = rest.row(faces(f, 0)).transpose(), b = rest.row(faces(f, 1)).transpose(),
             c = rest.row(faces(f, 2)).transpose();
  const double longest = std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
  return std::max(1, int(std::ceil(longest / spacing - 1e-9)));
}

void append_face_samples(const Points& rest, const Triangles& faces, int f, double spacing,
                         std::vector<SkinFaceSample>& out) {
  const Vec3 a = rest.row(faces(f, 0)).transpose(), b = rest.row(faces(f, 1)).transpose(),
             c = rest.row(faces(f, 2)).transpose();
  const double area = 0.5 * (b - a).cross(c - a).norm();
  const int n = face_subdivisions(rest, faces, f, spacing);
  const double w = area / double(n * n), inv = 1.0 / n;
  // Sub-triangle (i, j): corners λ = (i, j), (i+1, j), (i, j+1) / n ("up", centroid
  // at + 1/3) for i + j ≤ n − 1, and (i+1, j), (i, j+1), (i+1, j+1) / n ("down",
  // centroid at + 2/3) for i + j ≤ n − 2: n(n+1)/2 + n(n−1)/2 = n² in all.
  for (int i = 0; i < n; ++i)
    for (int j = 0; i + j < n; ++j)
      for (int down = 0; down < 2; ++down) {
        if (down && i + j > n - 2) continue;
        const double o = down ? 2.0 / 3.0 : 1.0 / 3.0;
        const double l1 = (i + o) * inv, l2 = (j + o) * inv;
        out.push_back({f, Vec3(1.0 - l1 - l2, l1, l2), w});
      }
}

void check_contact_sampling(double pressure_stiffness, double spacing, const std::string& what) {
  require(std::isfinite(pressure_stiffness) && pressure_stiffness > 0, what, ": pressure stiffness ",
          pressure_stiffness, " N/m^3, expected a finite number > 0");
  require(std::isfinite(spacing) && spacing > 0, what, ": contact sample spacing ", spacing,
          " m, expected a finite number > 0");
}

}  // namespace sflsh
