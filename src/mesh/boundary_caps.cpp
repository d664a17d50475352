#include "sflsh/mesh/boundary_caps.hpp"

#include <algorithm>
#include <array>
#include <map>

#include "sflsh/core/error.hpp"
#include "sflsh/mesh/geometry_set.hpp"
#include "sflsh/mesh/tet_quality.hpp"

namespace sflsh {
namespace {

using Face = std::array<int, 3>;

Face sorted_face(int a, int b, int c) {
  Face f{a, b, c};
  std::sort(f.begin(), f.end());
  return f;
}

// Face i of tet t is the one opposite its node i.
Face tet_face(const Tets& e, int t, int i) {
  int v[3], m = 0;
  for (int j = 0; j < 4; ++j)
    if (j != i) v[m++] = e(t, j);
  return sorted_face(v[0], v[1], v[2]);
}

/// How many tets hold each face and each node (#N nodes).
void count_faces_and_node_tets(const Tets& e, int N, std::map<Face, int>& face_count, std::vector<int>& node_tets) {
  node_tets.assign(size_t(N), 0);
  for (int t = 0; t < int(e.rows()); ++t)
    for (int i = 0; i < 4; ++i) {
      ++face_count[tet_face(e, t, i)];
      ++node_tets[size_t(e(t, i))];
    }
}

/// Whether tet t is inverted or below `floor_deg` at some geometry of `set`.
bool bad_somewhere(const GeometrySet& set, const Tets& e, int t, double floor_deg) {
  const TetNodes v{e(t, 0), e(t, 1), e(t, 2), e(t, 3)};
  return replacement_accepted(set, {}, {v}, floor_deg);  // removing it would help some geometry
}

}  // namespace

BoundaryCapReport remove_bad_boundary_caps(Tets& elements, const GeometrySet& set,
                                           const std::vector<char>& on_surface, double floor_deg,
                                           std::vector<int>* kept, const std::vector<char>* bad_elsewhere) {
  require(!set.empty(), "remove_bad_boundary_caps: no geometry");
  const int N = int(set.front().rows()), T = int(elements.rows());
  require(int(on_surface.size()) == N, "remove_bad_boundary_caps: ", on_surface.size(), " surface flags for ", N,
          " nodes");
  const Tets& e = elements;
  BoundaryCapReport rep;
  std::vector<char> alive(T, 1);
  std::map<Face, int> face_count;  // faces of the alive tets
  std::vector<int> node_tets;
  count_faces_and_node_tets(e, N, face_count, node_tets);
  // Boundary faces per edge (a < b), kept up to date as tets go.
  std::map<std::pair<int, int>, int> edge_boundary;
  auto edge = [](int a, int b) { return std::make_pair(std::min(a, b), std::max(a, b)); };
  auto add_face = [&](const Face& f, int s) {
    edge_boundary[edge(f[0], f[1])] += s;
    edge_boundary[edge(f[1], f[2])] += s;
    edge_boundary[edge(f[0], f[2])] += s;
  };
  for (const auto& [f, c] : face_count)
    if (c == 1) add_face(f, 1);

  require(!bad_elsewhere || int(bad_elsewhere->size()) == T, "remove_bad_boundary_caps: ",
          bad_elsewhere ? bad_elsewhere->size() : 0, " flags for ", T, " tets");
  auto is_bad = [&](int t) { return (bad_elsewhere && (*bad_elsewhere)[size_t(t)]) || bad_somewhere(set, e, t, floor_deg); };
  for (bool changed = true; changed;) {
    changed = false;
    for (int t = 0; t < T; ++t) {
      if (!alive[t]) continue;
      bool all_surface = true;
      for (int i = 0; i < 4; ++i) all_surface = all_surface && on_surface[e(t, i)];
      if (!all_surface) continue;
      int boundary[4], nb = 0;
      for (int i = 0; i < 4; ++i) {
        boundary[i] = face_count[tet_face(e, t, i)] == 1;
        nb += boundary[i];
      }
      if (nb != 2 || !is_bad(t)) continue;
      // The boundary faces are opposite c and d; they share edge (a, b).
      int cd[2], nc = 0;
      for (int i = 0; i < 4; ++i)
        if (boundary[i]) cd[nc++] = e(t, i);
      bool ok = edge_boundary[edge(cd[0], cd[1])] == 0;
      for (int i = 0; i < 4; ++i) ok = ok && node_tets[e(t, i)] > 1;
      if (!ok) continue;
      alive[t] = 0;
      ++rep.removed;
      changed = true;
      for (int i = 0; i < 4; ++i) {
        const Face f = tet_face(e, t, i);
        if (boundary[i]) {
          add_face(f, -1);  // was boundary, now gone
          face_count.erase(f);
        } else {
          face_count[f] = 1;  // now boundary
          add_face(f, 1);
        }
        --node_tets[e(t, i)];
      }
    }
  }
  std::vector<int> keep;
  for (int t = 0; t < T; ++t)
    if (alive[t]) keep.push_back(t);
  for (int t : keep) {
    bool all_surface = true;
    for (int i = 0; i < 4; ++i) all_surface = all_surface && on_surface[e(t, i)];
    rep.kept_bad += all_surface && is_bad(t);
  }
  Tets out(keep.size(), 4);
  for (size_t i = 0; i < keep.size(); ++i) out.row(Eigen::Index(i)) = e.row(keep[i]);
  elements = out;
  if (kept) *kept = keep;
  return rep;
}

BoundaryCapReport remove_bad_boundary_caps(TetMesh& mesh, const std::vector<char>& on_surface, double floor_deg,
                                           std::vector<int>* kept) {
  return remove_bad_boundary_caps(mesh.elements, GeometrySet{mesh.nodes}, on_surface, floor_deg, kept, nullptr);
}

BoundaryCapReport remove_bad_boundary_ears(Tets& elements, const GeometrySet& set,
                                           const std::vector<char>& on_surface, double floor_deg,
                                           std::vector<int>* kept_tets, std::vector<int>* kept_nodes) {
  require(!set.empty(), "remove_bad_boundary_ears: no geometry");
  const int N = int(set.front().rows()), T = int(elements.rows());
  require(int(on_surface.size()) == N, "remove_bad_boundary_ears: ", on_surface.size(), " surface flags for ", N,
          " nodes");
  const Tets& e = elements;
  BoundaryCapReport rep;
  std::vector<char> alive(T, 1), node_alive(N, 1);
  std::map<Face, int> face_count;  // faces of the alive tets
  std::vector<int> node_tets;
  count_faces_and_node_tets(e, N, face_count, node_tets);
  // The apex of tet t when three of its faces are boundary faces (else −1).
  auto ear_apex = [&](int t) {
    int nb = 0, apex = -1;
    for (int i = 0; i < 4; ++i) {
      if (face_count[tet_face(e, t, i)] == 1)
        ++nb;
      else
        apex = e(t, i);  // the face opposite the apex is the only interior one
    }
    return nb == 3 ? apex : -1;
  };
  auto is_bad = [&](int t) {
    bool all_surface = true;
    for (int i = 0; i < 4; ++i) all_surface = all_surface && on_surface[e(t, i)];
    return all_surface && bad_somewhere(set, e, t, floor_deg);
  };
  for (bool changed = true; changed;) {
    changed = false;
    for (int t = 0; t < T; ++t) {
      if (!alive[t] || !is_bad(t)) continue;
      const int apex = ear_apex(t);
      if (apex < 0 || node_tets[apex] != 1) continue;
      alive[t] = 0;
      node_alive[apex] = 0;
      ++rep.removed;
      changed = true;
      for (int i = 0; i < 4; ++i) {
        const Face f = tet_face(e, t, i);
        if (--face_count[f] == 0) face_count.erase(f);  // the base stays, now a boundary face
        --node_tets[e(t, i)];
      }
    }
  }
  std::vector<int> keep, new_index(N, -1), nodes;
  for (int n = 0; n < N; ++n)
    if (node_alive[n]) {
      new_index[n] = int(nodes.size());
      nodes.push_back(n);
    }
  for (int t = 0; t < T; ++t)
    if (alive[t]) {
      keep.push_back(t);
      rep.kept_bad += ear_apex(t) >= 0 && is_bad(t);
    }
  Tets out(keep.size(), 4);
  for (size_t i = 0; i < keep.size(); ++i)
    for (int c = 0; c < 4; ++c) out(Eigen::Index(i), c) = new_index[e(keep[i], c)];
  elements = out;
  if (kept_tets) *kept_tets = keep;
  if (kept_nodes) *kept_nodes = nodes;
  return rep;
}

BoundaryCapReport remove_bad_boundary_ears(TetMesh& mesh, const std::vector<char>& on_surface, double floor_deg,
                                           std::vector<int>* kept_tets, std::vector<int>* kept_nodes) {
  std::vector<int> nodes;
  const BoundaryCapReport rep =
      remove_bad_boundary_ears(mesh.elements, GeometrySet{mesh.nodes}, on_surface, floor_deg, kept_tets, &nodes);
  Points x(nodes.size(), 3);
  for (size_t i = 0; i < nodes.size(); ++i) x.row(Eigen::Index(i)) = mesh.nodes.row(nodes[i]);
  mesh.nodes = x;
  if (kept_nodes) *kept_nodes = nodes;
  return rep;
}

}  // namespace sflsh
