#include "sflsh/mesh/tet_flips.hpp"

#include <algorithm>
#include <array>
#include <map>

#include "sflsh/core/error.hpp"
#include "sflsh/mesh/geometry_set.hpp"
#include "sflsh/mesh/tet_quality.hpp"

namespace sflsh {
namespace {

using Face = std::array<int, 3>;
using Tet = TetNodes;

Face key(int a, int b, int c) {
  Face f{a, b, c};
  std::sort(f.begin(), f.end());
  return f;
}

// Orients the candidate tets alike at the reference geometry (all positive if
// the flip is valid there); false if one is degenerate or they disagree.
bool orient_alike_at_reference(const GeometrySet& set, std::vector<Tet>& tets) {
  int sign = 0;
  for (Tet& t : tets) {
    const double v = tet_quality_at(set.front(), t).signed_volume;
    const int s = v > 0 ? 1 : (v < 0 ? -1 : 0);
    if (s == 0 || (sign != 0 && s != sign)) return false;
    sign = s;
  }
  for (Tet& t : tets)
    if (sign < 0) std::swap(t[2], t[3]);
  return true;
}

// The new tets fill exactly the old ones (the flip is geometric, not just
// combinatorial): equal total volume, relative to the old one, at every
// geometry where the old tets are all positive (where one is not, the fresh
// ones' positivity is what replacement_accepted asks).
bool same_volume(const GeometrySet& set, const std::vector<Tet>& fresh, const std::vector<Tet>& old) {
  for (const Points& x : set) {
    double a = 0, b = 0;
    bool old_valid = true;
    for (const Tet& t : fresh) a += std::abs(tet_quality_at(x, t).signed_volume);
    for (const Tet& t : old) {
      const double v = tet_quality_at(x, t).signed_volume;
      old_valid = old_valid && v > 0;
      b += v;
    }
    if (old_valid && !(std::abs(a - b) <= 1e-9 * b)) return false;
  }
  return true;
}

// The tets being flipped, with the face and edge adjacency kept up to date;
// new tets are appended, replaced ones marked dead.
struct FlipMesh {
  std::vector<Tet> tets;
  std::vector<int> origin;  // input tet each tet descends from
  std::vector<char> alive;
  std::map<Face, std::vector<int>> face_tets;
  std::map<std::pair<int, int>, std::vector<int>> edge_tets;

  static std::pair<int, int> edge(int a, int b) { return std::make_pair(std::min(a, b), std::max(a, b)); }

  explicit FlipMesh(const Tets& elements)
      : tets(elements.rows()), origin(elements.rows()), alive(tets.size(), 1) {
    for (int t = 0; t < int(elements.rows()); ++t) {
      for (int i = 0; i < 4; ++i) tets[t][i] = elements(t, i);
      origin[t] = t;
    }
    for (size_t t = 0; t < tets.size(); ++t) link(int(t), true);
  }
  void link(int t, bool add) {
    const Tet& v = tets[t];
    for (int i = 0; i < 4; ++i) {
      auto& f = face_tets[key(v[(i + 1) % 4], v[(i + 2) % 4], v[(i + 3) % 4])];
      if (add) f.push_back(t); else f.erase(std::find(f.begin(), f.end(), t));
      for (int j = i + 1; j < 4; ++j) {
        auto& e = edge_tets[edge(v[i], v[j])];
        if (add) e.push_back(t); else e.erase(std::find(e.begin(), e.end(), t));
      }
    }
  }
  void replace(const std::vector<int>& old, const std::vector<Tet>& fresh) {
    for (int t : old) link(t, false), alive[t] = 0;
    for (const Tet& n : fresh) {
      tets.push_back(n);
      alive.push_back(1);
      origin.push_back(origin[old[0]]);
      link(int(tets.size()) - 1, true);
    }
  }
  /// Writes the live tets back to `elements` (and their origins to `parent`).
  void finish(Tets& elements, std::vector<int>* parent) const {
    std::vector<int> keep;
    for (size_t t = 0; t < tets.size(); ++t)
      if (alive[t]) keep.push_back(int(t));
    elements.resize(Eigen::Index(keep.size()), 4);
    if (parent) parent->resize(keep.size());
    for (size_t i = 0; i < keep.size(); ++i) {
      for (int k = 0; k < 4; ++k) elements(Eigen::Index(i), k) = tets[keep[i]][k];
      if (parent) (*parent)[i] = origin[keep[i]];
    }
  }
};

/// Smallest dihedral angle (deg) of tet t over the geometries, −1 if inverted at one.
double worst_over_set(const GeometrySet& set, const Tet& t) {
  double worst = 180;
  for (const Points& x : set) worst = std::min(worst, worst_dihedral_deg(x, {t}));
  return worst;
}

/// The frame of both flip passes: up to `rounds` sweeps over the tets alive
/// when each sweep starts; every live one rated below `target_deg` (or
/// inverted) at some geometry of `set` is offered to `try_flip(t)` (true when
/// it flipped t away), until a sweep flips nothing. Then the live tets are
/// written back to `elements`.
template <class TryFlip>
void sweep_bad_tets(Tets& elements, const GeometrySet& set, FlipMesh& m, double target_deg, int rounds,
                    std::vector<int>* parent, TryFlip try_flip) {
  for (int round = 0; round < rounds; ++round) {
    int made = 0;
    const size_t count = m.tets.size();
    for (size_t t = 0; t < count; ++t)
      if (m.alive[t] && worst_over_set(set, m.tets[t]) < target_deg) made += try_flip(t);
    if (made == 0) break;
  }
  m.finish(elements, parent);
}

}  // namespace

TetFlipReport flip_bad_tets(Tets& elements, const GeometrySet& set, double target_deg, int rounds,
                            std::vector<int>* parent) {
  require(!set.empty(), "flip_bad_tets: no geometry");
  TetFlipReport rep;
  rep.min_dihedral_before = tet_quality_report(TetMesh{set.front(), elements}).min_dihedral_deg;
  FlipMesh m(elements);
  std::vector<Tet>& tets = m.tets;
  auto& face_tets = m.face_tets;
  auto& edge_tets = m.edge_tets;
  const auto edge = FlipMesh::edge;
  const Points& x = set.front();

  sweep_bad_tets(elements, set, m, target_deg, rounds, parent, [&](size_t t) {
      bool done = false;
      // 2-3 across each interior face.
      for (int i = 0; i < 4 && !done; ++i) {
        const Tet& v = tets[t];
        const int a = v[i];
        const Face f = key(v[(i + 1) % 4], v[(i + 2) % 4], v[(i + 3) % 4]);
        const std::vector<int>& ft = face_tets[f];
        if (ft.size() != 2) continue;
        const int u = ft[0] == int(t) ? ft[1] : ft[0];
        int e = -1;
        for (int k = 0; k < 4; ++k)
          if (std::find(f.begin(), f.end(), tets[u][k]) == f.end()) e = tets[u][k];
        if (!edge_tets[edge(a, e)].empty()) continue;  // the new edge exists already
        std::vector<Tet> fresh = {{f[0], f[1], a, e}, {f[1], f[2], a, e}, {f[2], f[0], a, e}};
        const std::vector<Tet> old = {tets[t], tets[u]};
        if (orient_alike_at_reference(set, fresh) && same_volume(set, fresh, old) &&
            replacement_accepted(set, fresh, old, target_deg)) {
          m.replace({int(t), u}, fresh);
          ++rep.flips_2_3;
          done = true;
        }
      }
      // 3-2 around each edge with a closed ring of three tets.
      for (int i = 0; i < 4 && !done; ++i)
        for (int j = i + 1; j < 4 && !done; ++j) {
          const int a = tets[t][i], b = tets[t][j];
          const std::vector<int> ring = edge_tets[edge(a, b)];
          if (ring.size() != 3) continue;
          std::vector<int> others;
          for (int r : ring)
            for (int k = 0; k < 4; ++k)
              if (tets[r][k] != a && tets[r][k] != b &&
                  std::find(others.begin(), others.end(), tets[r][k]) == others.end())
                others.push_back(tets[r][k]);
          if (others.size() != 3) continue;
          bool closed = true;  // every face (a, b, c) shared by two tets of the ring
          for (int c : others) closed = closed && face_tets[key(a, b, c)].size() == 2;
          if (!closed || !face_tets[key(others[0], others[1], others[2])].empty()) continue;
          std::vector<Tet> fresh = {{others[0], others[1], others[2], a}, {others[0], others[1], others[2], b}};
          // The two lie on opposite sides of the new face: each oriented on its own at the
          // reference, and a, b on different sides of the face (others) there.
          const Vec3 p0 = x.row(others[0]).transpose(), p1 = x.row(others[1]).transpose(),
                     p2 = x.row(others[2]).transpose();
          const Vec3 nrm = (p1 - p0).cross(p2 - p0);
          const double sa = nrm.dot(x.row(a).transpose() - p0), sb = nrm.dot(x.row(b).transpose() - p0);
          const std::vector<Tet> old = {tets[ring[0]], tets[ring[1]], tets[ring[2]]};
          if (sa * sb < 0 && orient_at_reference(set, fresh) && same_volume(set, fresh, old) &&
              replacement_accepted(set, fresh, old, target_deg)) {
            m.replace(ring, fresh);
            ++rep.flips_3_2;
            done = true;
          }
        }
      return done;
  });
  rep.min_dihedral_after = tet_quality_report(TetMesh{set.front(), elements}).min_dihedral_deg;
  return rep;
}

TetFlipReport flip_bad_tets(TetMesh& mesh, double target_deg, int rounds, std::vector<int>* parent) {
  return flip_bad_tets(mesh.elements, GeometrySet{mesh.nodes}, target_deg, rounds, parent);
}

TetFlipReport flip_bad_boundary_edges(Tets& elements, const GeometrySet& set, const std::vector<char>& on_surface,
                                      double target_deg, int rounds, std::vector<int>* parent) {
  require(!set.empty(), "flip_bad_boundary_edges: no geometry");
  require(int(on_surface.size()) == set.front().rows(), "flip_bad_boundary_edges: ", on_surface.size(),
          " surface flags for ", set.front().rows(), " nodes");
  TetFlipReport rep;
  rep.min_dihedral_before = tet_quality_report(TetMesh{set.front(), elements}).min_dihedral_deg;
  FlipMesh m(elements);
  sweep_bad_tets(elements, set, m, target_deg, rounds, parent, [&](size_t t) {
      bool done = false;
      for (int i = 0; i < 4 && !done; ++i)
        for (int j = i + 1; j < 4 && !done; ++j) {
          const int q = m.tets[t][i], r = m.tets[t][j];
          const std::vector<int> fan = m.edge_tets[FlipMesh::edge(q, r)];
          if (fan.size() != 2 || !on_surface[q] || !on_surface[r]) continue;
          // The fan's two tets share the face (q, r, i); a and b are their other nodes.
          int node_a = -1, node_b = -1, inner = -1;
          for (int k = 0; k < 4; ++k) {
            const int v = m.tets[fan[0]][k];
            if (v == q || v == r) continue;
            if (std::find(m.tets[fan[1]].begin(), m.tets[fan[1]].end(), v) != m.tets[fan[1]].end())
              inner = v;
            else
              node_a = v;
          }
          for (int k = 0; k < 4; ++k) {
            const int v = m.tets[fan[1]][k];
            if (v != q && v != r && v != inner) node_b = v;
          }
          if (inner < 0 || node_a < 0 || node_b < 0 || !on_surface[node_a] || !on_surface[node_b]) continue;
          // Both outer faces on the boundary, the shared one inside, and a–b not an edge yet.
          if (m.face_tets[key(node_a, q, r)].size() != 1 || m.face_tets[key(node_b, q, r)].size() != 1 ||
              m.face_tets[key(inner, q, r)].size() != 2 || !m.edge_tets[FlipMesh::edge(node_a, node_b)].empty())
            continue;
          // q and r on opposite sides of the plane (a, b, i) at every geometry (else the two
          // new tets would overlap there): with the orientation fixed at the reference, both
          // new tets positive at a geometry says exactly that.
          const Points& x = set.front();
          const Vec3 pa = x.row(node_a).transpose(),
                     n = (Vec3(x.row(node_b).transpose()) - pa).cross(Vec3(x.row(inner).transpose()) - pa);
          if (n.dot(Vec3(x.row(q).transpose()) - pa) * n.dot(Vec3(x.row(r).transpose()) - pa) >= 0) continue;
          std::vector<Tet> fresh = {{node_a, node_b, q, inner}, {node_a, node_b, r, inner}};
          if (!orient_at_reference(set, fresh) ||
              !replacement_accepted(set, fresh, {m.tets[fan[0]], m.tets[fan[1]]}, target_deg))
            continue;
          m.replace(fan, fresh);
          ++rep.flips_2_2;
          done = true;
        }
      return done;
  });
  rep.min_dihedral_after = tet_quality_report(TetMesh{set.front(), elements}).min_dihedral_deg;
  return rep;
}

TetFlipReport flip_bad_boundary_edges(TetMesh& mesh, const std::vector<char>& on_surface, double target_deg,
                                      int rounds, std::vector<int>* parent) {
  return flip_bad_boundary_edges(mesh.elements, GeometrySet{mesh.nodes}, on_surface, target_deg, rounds, parent);
}

}  // namespace sflsh
