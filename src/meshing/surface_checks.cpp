// Surface checks: edge/vertex manifoldness, orientation, components, Euler
// characteristic, volume, and self-intersection through CGAL (kept inside this
// file so that no public header pulls CGAL in).
#include "sflsh/meshing/surface_checks.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <iomanip>
#include <limits>
#include <numeric>
#include <sstream>
#include <unordered_map>
#include <vector>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>

#include "sflsh/core/error.hpp"

namespace sflsh {
namespace {

/// Union-find over 0..n-1 (path halving).
struct DisjointSets {
  std::vector<int> parent;
  explicit DisjointSets(int n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  int find(int i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  }
  void unite(int a, int b) { parent[find(a)] = find(b); }
};

std::uint64_t edge_key(int a, int b) {
  if (a > b) std::swap(a, b);
  return (std::uint64_t(std::uint32_t(a)) << 32) | std::uint32_t(b);
}

/// Per undirected edge: the faces using it and how often it runs a->b (a<b).
struct EdgeUse {
  int count = 0;
  int forward = 0;  // traversals from the smaller to the larger index
  int first_face = -1;
};

bool run_self_intersection(const Points& V, const Triangles& F) {
  using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
  using Mesh = CGAL::Surface_mesh<Kernel::Point_3>;
  Mesh mesh;
  std::vector<Mesh::Vertex_index> vid(V.rows());
  for (int i = 0; i < V.rows(); ++i) vid[i] = mesh.add_vertex(Kernel::Point_3(V(i, 0), V(i, 1), V(i, 2)));
  for (int f = 0; f < F.rows(); ++f) {
    const auto face = mesh.add_face(vid[F(f, 0)], vid[F(f, 1)], vid[F(f, 2)]);
    require(face != Mesh::null_face(), "check_surface: face ", f, " could not be added to a halfedge mesh");
  }
  return CGAL::Polygon_mesh_processing::does_self_intersect(mesh);
}

}  // namespace

bool SurfaceReport::is_valid_body_surface() const {
  return is_closed && is_manifold && consistently_oriented && num_components == 1 && genus == 0 &&
         signed_volume > 0.0 && !(self_intersection_tested && self_intersects);
}

std::string SurfaceReport::describe() const {
  std::ostringstream os;
  os << num_vertices << " vertices, " << num_faces << " faces, " << (is_closed ? "closed" : "open") << ", "
     << (is_manifold ? "manifold" : "non-manifold") << ", "
     << (consistently_oriented ? "oriented" : "inconsistently oriented") << ", " << num_components
     << (num_components == 1 ? " component" : " components") << ", ";
  if (genus >= 0)
    os << "genus " << genus;
  else
    os << "Euler characteristic " << euler_characteristic;
  os << ", volume " << std::setprecision(4) << signed_volume << " m^3, ";
  if (!self_intersection_tested)
    os << "self-intersection not tested";
  else
    os << (self_intersects ? "self-intersecting" : "no self-intersections");
  os << ", height " << std::fixed << std::setprecision(3) << height() << " m";
  return os.str();
}

namespace {

/// Whether the link of vertex v (the edges opposite to it in its faces `fan`)
/// is one connected path or cycle.
bool link_is_one_piece(const Triangles& F, int v, const std::vector<int>& fan) {
  std::vector<std::pair<int, int>> link;  // opposite edge per face
  std::vector<int> nodes;
  for (int f : fan) {
    int k = 0;
    while (F(f, k) != v) ++k;
    const int a = F(f, (k + 1) % 3), b = F(f, (k + 2) % 3);
    link.emplace_back(a, b);
    nodes.push_back(a);
    nodes.push_back(b);
  }
  std::sort(nodes.begin(), nodes.end());
  nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
  DisjointSets link_sets(int(nodes.size()));
  std::vector<int> degree(nodes.size(), 0);
  auto local = [&](int x) { return int(std::lower_bound(nodes.begin(), nodes.end(), x) - nodes.begin()); };
  for (const auto& [a, b] : link) {
    const int la = local(a), lb = local(b);
    link_sets.unite(la, lb);
    ++degree[la];
    ++degree[lb];
  }
  int parts = 0;
  bool ok = true;
  for (size_t i = 0; i < nodes.size(); ++i) {
    if (link_sets.find(int(i)) == int(i)) ++parts;
    if (degree[i] > 2) ok = false;
  }
  return parts == 1 && ok;
}

}  // namespace

SurfaceReport check_surface(const Points& V, const Triangles& F, bool test_self_intersection) {
  SurfaceReport r;
  r.num_vertices = int(V.rows());
  r.num_faces = int(F.rows());
  require(V.allFinite(), "check_surface: vertex array (", V.rows(), " by 3) holds a non-finite value");
  for (int f = 0; f < F.rows(); ++f)
    for (int c = 0; c < 3; ++c)
      require(F(f, c) >= 0 && F(f, c) < V.rows(), "check_surface: face ", f, " corner ", c, " = ", F(f, c),
              ", expected an index in [0, ", V.rows(), ")");

  // Edges: count uses and directions.
  std::unordered_map<std::uint64_t, EdgeUse> edges;
  edges.reserve(size_t(F.rows()) * 2);
  std::vector<char> referenced(V.rows(), 0);
  DisjointSets face_sets(int(F.rows()));
  for (int f = 0; f < F.rows(); ++f) {
    const int a = F(f, 0), b = F(f, 1), c = F(f, 2);
    if (a == b || b == c || a == c) ++r.num_degenerate_faces;
    referenced[a] = referenced[b] = referenced[c] = 1;
    for (int k = 0; k < 3; ++k) {
      const int u = F(f, k), w = F(f, (k + 1) % 3);
      if (u == w) continue;
      EdgeUse& e = edges[edge_key(u, w)];
      ++e.count;
      if (u < w) ++e.forward;
      if (e.first_face < 0)
        e.first_face = f;
      else
        face_sets.unite(f, e.first_face);
    }
  }
  r.num_edges = int(edges.size());
  double sum_len = 0.0;
  r.min_edge_length = std::numeric_limits<double>::infinity();
  for (const auto& [key, e] : edges) {
    if (e.count == 1) ++r.num_boundary_edges;
    if (e.count >= 3) ++r.num_nonmanifold_edges;
    if (e.count == 2 && e.forward != 1) ++r.num_misoriented_edges;
    const int a = int(key >> 32), b = int(key & 0xffffffffu);
    const double len = (V.row(a) - V.row(b)).norm();
    sum_len += len;
    r.min_edge_length = std::min(r.min_edge_length, len);
    r.max_edge_length = std::max(r.max_edge_length, len);
  }
  if (edges.empty()) r.min_edge_length = 0.0;
  r.mean_edge_length = edges.empty() ? 0.0 : sum_len / double(edges.size());

  // Vertex manifoldness: the link of every vertex (edges opposite to it in its
  // faces) must be one connected path or cycle.
  std::vector<std::vector<int>> vertex_faces(V.rows());
  for (int f = 0; f < F.rows(); ++f)
    for (int c = 0; c < 3; ++c) vertex_faces[F(f, c)].push_back(f);
  for (int v = 0; v < V.rows(); ++v) {
    const auto& fan = vertex_faces[v];
    if (fan.empty()) {
      ++r.num_unreferenced_vertices;
      continue;
    }
    if (!link_is_one_piece(F, v, fan)) ++r.num_nonmanifold_vertices;
  }

  r.is_closed = r.num_faces > 0 && r.num_boundary_edges == 0 && r.num_nonmanifold_edges == 0;
  r.is_manifold = r.num_faces > 0 && r.num_nonmanifold_edges == 0 && r.num_nonmanifold_vertices == 0 &&
                  r.num_degenerate_faces == 0;
  r.consistently_oriented = r.num_nonmanifold_edges == 0 && r.num_misoriented_edges == 0;

  for (int f = 0; f < F.rows(); ++f)
    if (face_sets.find(f) == f) ++r.num_components;
  const int used_vertices = r.num_vertices - r.num_unreferenced_vertices;
  r.euler_characteristic = used_vertices - r.num_edges + r.num_faces;
  if (r.is_closed && r.is_manifold && (2 * r.num_components - r.euler_characteristic) % 2 == 0)
    r.genus = (2 * r.num_components - r.euler_characteristic) / 2;

  // Volume by the divergence theorem: Σ v0·(v1×v2)/6 (exact for closed surfaces).
  for (int f = 0; f < F.rows(); ++f) {
    const Vec3 a = V.row(F(f, 0)), b = V.row(F(f, 1)), c = V.row(F(f, 2));
    r.signed_volume += a.dot(b.cross(c)) / 6.0;
    r.area += 0.5 * (b - a).cross(c - a).norm();
  }
  bool first = true;
  for (int v = 0; v < V.rows(); ++v) {
    if (!referenced[v]) continue;
    const Vec3 p = V.row(v);
    if (first) {
      r.bbox_min = r.bbox_max = p;
      first = false;
    }
    r.bbox_min = r.bbox_min.cwiseMin(p);
    r.bbox_max = r.bbox_max.cwiseMax(p);
  }

  if (test_self_intersection && r.is_manifold && r.consistently_oriented && r.num_unreferenced_vertices == 0) {
    r.self_intersects = run_self_intersection(V, F);
    r.self_intersection_tested = true;
  }
  return r;
}

double winding_number(const Points& V, const Triangles& F, const Vec3& p) {
  // Solid angle of each triangle seen from p (van Oosterom & Strackee 1983),
  // summed and divided by 4π.
  double total = 0.0;
  for (int f = 0; f < F.rows(); ++f) {
    const Vec3 a = V.row(F(f, 0)).transpose() - p;
    const Vec3 b = V.row(F(f, 1)).transpose() - p;
    const Vec3 c = V.row(F(f, 2)).transpose() - p;
    const double la = a.norm(), lb = b.norm(), lc = c.norm();
    const double num = a.dot(b.cross(c));
    const double den = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
    total += 2.0 * std::atan2(num, den);
  }
  return total / (4.0 * M_PI);
}

}  // namespace sflsh
