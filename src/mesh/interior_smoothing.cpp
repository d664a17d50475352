#include "sflsh/mesh/interior_smoothing.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "sflsh/core/error.hpp"
#include "sflsh/mesh/tet_quality.hpp"

namespace sflsh {
namespace {

struct MeshScan {
  int below = 0, inverted = 0;
  double min_deg = std::numeric_limits<double>::infinity();
};

MeshScan scan(const TetMesh& mesh, double target_deg, std::vector<char>* bad) {
  MeshScan s;
  if (bad) bad->assign(mesh.num_elements(), 0);
  for (int t = 0; t < mesh.num_elements(); ++t) {
    const TetQuality q = tet_quality(mesh, t);
    const bool inverted = !(q.signed_volume > 0);
    s.inverted += inverted;
    s.min_deg = std::min(s.min_deg, q.min_dihedral_deg);
    if (q.min_dihedral_deg < target_deg || inverted) {
      ++s.below;
      if (bad) (*bad)[t] = 1;
    }
  }
  return s;
}

// The smallest dihedral angle (deg) of node n's star with n at x if no tet of
// it is inverted; otherwise -1 - (number of inverted tets) - a term in (0, 1)
// growing with their total negative volume (relative to h^3), so a move that
// untangles part of a folded star counts as an improvement.
double star_score(const TetMesh& mesh, const std::vector<int>& star, int n, const Vec3& x, double h) {
  double worst = std::numeric_limits<double>::infinity(), negative = 0;
  int inverted = 0;
  for (int t : star) {
    Vec3 p[4];
    for (int i = 0; i < 4; ++i) {
      const int m = mesh.elements(t, i);
      p[i] = m == n ? x : Vec3(mesh.nodes.row(m).transpose());
    }
    const TetQuality q = tet_quality(p[0], p[1], p[2], p[3]);
    if (!(q.signed_volume > 0)) {
      ++inverted;
      negative += std::isfinite(q.signed_volume) ? -q.signed_volume : 1e300;
    }
    worst = std::min(worst, q.min_dihedral_deg);
  }
  if (inverted == 0) return worst;
  return -1.0 - inverted - std::tanh(negative / (h * h * h));
}

}  // namespace

InteriorSmoothingReport smooth_interior_nodes(TetMesh& mesh, const std::vector<NodeFreedom>& freedom,
                                              const Points& slide_normals, const InteriorSmoothingOptions& o,
                                              const std::function<Vec3(const Vec3&)>& project_to_surface) {
  const int N = mesh.num_nodes();
  require(int(freedom.size()) == N, "smooth_interior_nodes: ", freedom.size(), " freedom flags for ", N, " nodes");
  require(slide_normals.rows() == N || std::none_of(freedom.begin(), freedom.end(),
                                                    [](NodeFreedom f) { return f == NodeFreedom::Slide; }),
          "smooth_interior_nodes: ", slide_normals.rows(), " slide normals for ", N, " nodes");
  require(project_to_surface || std::none_of(freedom.begin(), freedom.end(),
                                             [](NodeFreedom f) { return f == NodeFreedom::Surface; }),
          "smooth_interior_nodes: Surface nodes need a projection onto the surface");
  InteriorSmoothingReport rep;
  std::vector<char> bad;
  const MeshScan before = scan(mesh, o.target_deg, &bad);
  rep.below_target_before = before.below;
  rep.min_dihedral_before = before.min_deg;
  rep.inverted_before = before.inverted;

  const std::vector<std::vector<int>> star = tet_stars(mesh);
  const std::vector<std::vector<int>> nbr = tet_node_neighbours(mesh);
  std::vector<Vec3> lattice;
  for (int a = -1; a <= 1; ++a)
    for (int b = -1; b <= 1; ++b)
      for (int c = -1; c <= 1; ++c)
        if (a || b || c) lattice.push_back(Vec3(a, b, c).normalized());

  const Points start = mesh.nodes;
  std::vector<double> reach(N, -1.0);  // allowed distance from start, set when a node is first visited
  std::vector<char> moved_ever(N, 0);
  for (int pass = 0; pass < o.passes; ++pass) {
    // Nodes of the tets below target, in index order.
    std::vector<int> nodes;
    for (int t = 0; t < mesh.num_elements(); ++t)
      if (bad[t])
        for (int i = 0; i < 4; ++i)
          if (freedom[mesh.elements(t, i)] != NodeFreedom::Fixed) nodes.push_back(mesh.elements(t, i));
    std::sort(nodes.begin(), nodes.end());
    nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
    if (nodes.empty()) break;
    rep.passes = pass + 1;
    int moved = 0;
    for (int n : nodes) {
      const Vec3 x = mesh.nodes.row(n).transpose();
      double h = std::numeric_limits<double>::infinity();
      for (int m : nbr[n]) h = std::min(h, (mesh.nodes.row(m).transpose() - x).norm());
      const double q0 = star_score(mesh, star[n], n, x, h);
      if (q0 >= o.target_deg) continue;
      const bool slide = freedom[n] == NodeFreedom::Slide, on_surface = freedom[n] == NodeFreedom::Surface;
      const Vec3 nu = slide ? Vec3(slide_normals.row(n).transpose()) : Vec3::Zero();
      auto project = [&](const Vec3& d) -> Vec3 { return slide ? Vec3(d - d.dot(nu) * nu) : d; };
      if (reach[n] < 0) reach[n] = o.max_displacement_fraction * h;
      const Vec3 x0 = start.row(n).transpose();

      std::vector<Vec3> cand;
      Vec3 centroid = Vec3::Zero();
      for (int m : nbr[n]) centroid += mesh.nodes.row(m).transpose();
      centroid /= double(nbr[n].size());
      cand.push_back(x + project(centroid - x));
      cand.push_back(x + 0.5 * project(centroid - x));
      std::vector<Vec3> dirs = lattice;
      // The normals of the faces opposite n in its worst tet: moving n off that face.
      int worst_t = -1;
      double worst_q = std::numeric_limits<double>::infinity();
      for (int t : star[n]) {
        const double q = tet_quality(mesh, t).min_dihedral_deg;
        if (q < worst_q) worst_q = q, worst_t = t;
      }
      if (worst_t >= 0) {
        Vec3 f[3];
        for (int k = 0, m = 0; k < 4; ++k)
          if (mesh.elements(worst_t, k) != n) f[m++] = mesh.nodes.row(mesh.elements(worst_t, k)).transpose();
        const Vec3 nrm = (f[1] - f[0]).cross(f[2] - f[0]);
        if (nrm.norm() > 0) dirs.push_back(nrm.normalized()), dirs.push_back(-nrm.normalized());
      }
      for (double step : {0.3, 0.1, 0.03})
        for (const Vec3& d : dirs) {
          const Vec3 p = project(d);
          if (p.norm() < 1e-3) continue;  // a direction along the slide normal
          cand.push_back(x + step * h * p.normalized());
        }
      double best = q0;
      Vec3 best_x = x;
      for (Vec3 y : cand) {
        if (on_surface) y = project_to_surface(y);
        if ((y - x0).norm() > reach[n]) continue;
        const double q = star_score(mesh, star[n], n, y, h);
        if (q > best + 1e-9) best = q, best_x = y;
      }
      if (best_x != x) {
        mesh.nodes.row(n) = best_x.transpose();
        moved_ever[n] = 1;
        ++moved;
        for (int t : star[n]) {
          const TetQuality q = tet_quality(mesh, t);
          bad[t] = q.min_dihedral_deg < o.target_deg || !(q.signed_volume > 0);
        }
      }
    }
    rep.moves += moved;
    if (moved == 0) break;
  }
  const MeshScan after = scan(mesh, o.target_deg, &bad);
  for (int t = 0; t < mesh.num_elements(); ++t) {
    bool all_fixed = true;
    for (int i = 0; i < 4; ++i) all_fixed = all_fixed && freedom[mesh.elements(t, i)] == NodeFreedom::Fixed;
    rep.below_target_all_fixed += bad[t] && all_fixed;
  }
  rep.below_target_after = after.below;
  rep.min_dihedral_after = after.min_deg;
  rep.inverted_after = after.inverted;
  for (int n = 0; n < N; ++n) {
    rep.nodes_moved += moved_ever[n];
    rep.max_displacement = std::max(rep.max_displacement, (mesh.nodes.row(n) - start.row(n)).norm());
  }
  return rep;
}

}  // namespace sflsh
