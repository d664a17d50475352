#include "sflsh/mesh/geometry_set.hpp"

#include <algorithm>
#include <utility>

#include "sflsh/mesh/tet_quality.hpp"

namespace sflsh {

TetQuality tet_quality_at(const Points& x, const TetNodes& t) {
  return tet_quality(x.row(t[0]).transpose(), x.row(t[1]).transpose(), x.row(t[2]).transpose(),
                     x.row(t[3]).transpose());
}

double worst_dihedral_deg(const Points& x, const std::vector<TetNodes>& tets) {
  double worst = 180;
  for (const TetNodes& t : tets) {
    const TetQuality q = tet_quality_at(x, t);
    if (!(q.signed_volume > 0)) return -1;
    worst = std::min(worst, q.min_dihedral_deg);
  }
  return worst;
}

bool replacement_accepted(const GeometrySet& set, const std::vector<TetNodes>& fresh,
                          const std::vector<TetNodes>& old, double cap_deg) {
  bool helps = false;
  for (const Points& x : set) {
    const double after = worst_dihedral_deg(x, fresh);
    if (after < 0) return false;
    const double a = std::min(after, cap_deg), b = std::min(worst_dihedral_deg(x, old), cap_deg);
    if (a < b) return false;
    helps = helps || a > b + 1e-9;
  }
  return helps;
}

bool orient_at_reference(const GeometrySet& set, std::vector<TetNodes>& tets) {
  for (TetNodes& t : tets) {
    const double v = tet_quality_at(set.front(), t).signed_volume;
    if (!(v != 0)) return false;
    if (v < 0) std::swap(t[2], t[3]);
  }
  return true;
}

}  // namespace sflsh
