#include "sflsh/mesh/sliver_repair.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "sflsh/core/error.hpp"
#include "sflsh/mesh/tet_quality.hpp"

namespace sflsh {
SliverRepairReport repair_slivers(TetMesh& mesh, const std::vector<char>& movable, const SliverRepairOptions& o) {
  const int N = mesh.num_nodes(), T = mesh.num_elements();
  require(int(movable.size()) == N, "repair_slivers: ", movable.size(), " movable flags for ", N, " nodes");
  const std::vector<std::vector<int>> star = tet_stars(mesh);
  std::vector<Vec3> lattice;
  for (int a = -1; a <= 1; ++a)
    for (int b = -1; b <= 1; ++b)
      for (int c = -1; c <= 1; ++c)
        if (a || b || c) lattice.push_back(Vec3(a, b, c).normalized());

  SliverRepairReport rep;
  auto count = [&](double* min_deg) {
    int below = 0;
    double m = std::numeric_limits<double>::infinity();
    for (int t = 0; t < T; ++t) {
      const double d = tet_quality(mesh, t).min_dihedral_deg;
      below += d < o.target_deg;
      m = std::min(m, d);
    }
    *min_deg = m;
    return below;
  };
  rep.slivers_before = count(&rep.min_dihedral_before);
  for (int pass = 0; pass < o.passes; ++pass) {
    int moved = 0;
    for (int t = 0; t < T; ++t) {
      if (tet_quality(mesh, t).min_dihedral_deg >= o.target_deg) continue;
      for (int i = 0; i < 4; ++i) {
        const int n = mesh.elements(t, i);
        if (!movable[n]) continue;
        const Vec3 x = mesh.nodes.row(n);
        double h = std::numeric_limits<double>::infinity();
        for (int s : star[n])
          for (int j = 0; j < 4; ++j)
            if (mesh.elements(s, j) != n) h = std::min(h, (mesh.nodes.row(mesh.elements(s, j)).transpose() - x).norm());
        std::vector<Vec3> dirs = lattice;
        {
          Vec3 f[3];
          for (int k = 0, m = 0; k < 4; ++k)
            if (k != i) f[m++] = mesh.nodes.row(mesh.elements(t, k));
          const Vec3 nrm = (f[1] - f[0]).cross(f[2] - f[0]);
          if (nrm.norm() > 0) dirs.push_back(nrm.normalized()), dirs.push_back(-nrm.normalized());
        }
        double best = star_min_dihedral(mesh, star[n], n, x);
        Vec3 best_x = x;
        for (double step : {0.3, 0.1, 0.03})
          for (const Vec3& d : dirs) {
            const Vec3 y = x + step * h * d;
            const double q = star_min_dihedral(mesh, star[n], n, y);
            if (q > best + 1e-9) best = q, best_x = y;
          }
        if (best_x != x) {
          mesh.nodes.row(n) = best_x.transpose();
          ++moved;
        }
      }
    }
    rep.moves += moved;
    if (moved == 0) break;
  }
  rep.slivers_after = count(&rep.min_dihedral_after);
  return rep;
}

}  // namespace sflsh
