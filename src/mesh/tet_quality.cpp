#include "sflsh/mesh/tet_quality.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace sflsh {

TetQuality tet_quality(const Vec3& x0, const Vec3& x1, const Vec3& x2, const Vec3& x3) {
  TetQuality q;
  const Vec3 p[4] = {x0, x1, x2, x3};
  q.signed_volume = (x1 - x0).dot((x2 - x0).cross(x3 - x0)) / 6.0;

  // Outward face normals scaled by face area; face i is opposite node i.
  // The interior dihedral angle at the edge shared by faces i and j is
  // pi - angle(n_i, n_j) (outward normals).
  static const int face[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  Vec3 n[4];
  double area_sum = 0;
  for (int i = 0; i < 4; ++i) {
    const Vec3& a = p[face[i][0]];
    const Vec3& b = p[face[i][1]];
    const Vec3& c = p[face[i][2]];
    n[i] = 0.5 * (b - a).cross(c - a);
    area_sum += n[i].norm();
  }
  // Orientation-independent: the face order above is outward for positive
  // tets; for negative ones every normal flips, which leaves angles unchanged.
  double mind = 180.0, maxd = 0.0;
  for (int i = 0; i < 4; ++i)
    for (int j = i + 1; j < 4; ++j) {
      const double ni = n[i].norm(), nj = n[j].norm();
      double angle = 0.0;
      if (ni > 0 && nj > 0) {
        const double c = std::clamp(n[i].dot(n[j]) / (ni * nj), -1.0, 1.0);
        angle = 180.0 - std::acos(c) * 180.0 / M_PI;
      }
      mind = std::min(mind, angle);
      maxd = std::max(maxd, angle);
    }
  q.min_dihedral_deg = mind;
  q.max_dihedral_deg = maxd;

  // Inradius r = 3V / total area; circumradius from the standard formula
  // R = |a^2 (b×c) + b^2 (c×a) + c^2 (a×b)| / (12 |V|) with edges from x0.
  const double vol = std::abs(q.signed_volume);
  if (vol > 0 && area_sum > 0) {
    const Vec3 a = x1 - x0, b = x2 - x0, c = x3 - x0;
    const Vec3 num = a.squaredNorm() * b.cross(c) + b.squaredNorm() * c.cross(a) + c.squaredNorm() * a.cross(b);
    const double R = num.norm() / (12.0 * vol);
    const double r = 3.0 * vol / area_sum;
    q.radius_ratio = R > 0 ? std::min(1.0, 3.0 * r / R) : 0.0;
  }
  return q;
}

TetQuality tet_quality(const TetMesh& mesh, int t) {
  const auto& e = mesh.elements;
  return tet_quality(mesh.nodes.row(e(t, 0)).transpose(), mesh.nodes.row(e(t, 1)).transpose(),
                     mesh.nodes.row(e(t, 2)).transpose(), mesh.nodes.row(e(t, 3)).transpose());
}

TetQualityReport tet_quality_report(const TetMesh& mesh, double sliver_threshold_deg) {
  TetQualityReport r;
  r.num_nodes = mesh.num_nodes();
  r.num_tets = mesh.num_elements();
  r.sliver_threshold_deg = sliver_threshold_deg;
  if (r.num_tets == 0) return r;
  r.min_volume = std::numeric_limits<double>::infinity();
  r.min_dihedral_deg = 180.0;
  r.min_radius_ratio = 1.0;
  double rr_sum = 0;
  for (int t = 0; t < r.num_tets; ++t) {
    const TetQuality q = tet_quality(mesh, t);
    if (!(q.signed_volume > 0)) ++r.num_inverted;
    r.total_volume += q.signed_volume;
    r.min_volume = std::min(r.min_volume, q.signed_volume);
    r.min_dihedral_deg = std::min(r.min_dihedral_deg, q.min_dihedral_deg);
    r.max_dihedral_deg = std::max(r.max_dihedral_deg, q.max_dihedral_deg);
    r.min_radius_ratio = std::min(r.min_radius_ratio, q.radius_ratio);
    rr_sum += q.radius_ratio;
    if (q.min_dihedral_deg < sliver_threshold_deg) ++r.num_below_threshold;
  }
  r.mean_radius_ratio = rr_sum / r.num_tets;
  return r;
}

std::string TetQualityReport::describe() const {
  std::ostringstream os;
  os << "tet mesh: " << num_nodes << " nodes, " << num_tets << " tets, volume " << total_volume * 1e3
     << " L\n"
     << "  dihedral angles: min " << min_dihedral_deg << " deg, max " << max_dihedral_deg << " deg; "
     << num_below_threshold << " tets below " << sliver_threshold_deg << " deg\n"
     << "  radius ratio: min " << min_radius_ratio << ", mean " << mean_radius_ratio << "\n"
     << "  smallest tet volume " << min_volume << " m^3, " << num_inverted << " inverted/degenerate";
  return os.str();
}

std::vector<std::vector<int>> tet_stars(const TetMesh& mesh) {
  std::vector<std::vector<int>> star(mesh.num_nodes());
  for (int t = 0; t < mesh.num_elements(); ++t)
    for (int i = 0; i < 4; ++i) star[mesh.elements(t, i)].push_back(t);
  return star;
}

std::vector<std::vector<int>> tet_node_neighbours(const TetMesh& mesh) {
  std::vector<std::vector<int>> nbr(mesh.num_nodes());
  for (int t = 0; t < mesh.num_elements(); ++t)
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j)
        if (i != j) nbr[mesh.elements(t, i)].push_back(mesh.elements(t, j));
  for (auto& n : nbr) {
    std::sort(n.begin(), n.end());
    n.erase(std::unique(n.begin(), n.end()), n.end());
  }
  return nbr;
}

double star_min_dihedral(const TetMesh& mesh, const std::vector<int>& star, int n, const Vec3& x) {
  double worst = std::numeric_limits<double>::infinity();
  for (int t : star) {
    Vec3 p[4];
    for (int i = 0; i < 4; ++i) {
      const int m = mesh.elements(t, i);
      p[i] = m == n ? x : Vec3(mesh.nodes.row(m).transpose());
    }
    const TetQuality q = tet_quality(p[0], p[1], p[2], p[3]);
    if (!(q.signed_volume > 0)) return -1.0;
    worst = std::min(worst, q.min_dihedral_deg);
  }
  return worst;
}

int orient_tets_positively(TetMesh& mesh) {
  int flipped = 0;
  for (int t = 0; t < mesh.num_elements(); ++t) {
    if (tet_quality(mesh, t).signed_volume < 0) {
      std::swap(mesh.elements(t, 2), mesh.elements(t, 3));
      ++flipped;
    }
  }
  return flipped;
}

}  // namespace sflsh
