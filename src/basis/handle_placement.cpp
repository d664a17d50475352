#include "sflsh/basis/handle_placement.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>
#include <random>
#include <vector>

#include "sflsh/asset/avatar.hpp"
#include "sflsh/fem/tet_operators.hpp"
#include "sflsh/core/error.hpp"

namespace sflsh::basis {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

struct Edge {
  int to;
  double length;
};

/// Undirected tet-edge graph with metric lengths |e|·(s_a + s_b)/2.
std::vector<std::vector<Edge>> edge_graph(const TetMesh& mesh, const VecX& scale) {
  std::vector<std::vector<Edge>> g(mesh.num_nodes());
  static const int pairs[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
  for (int e = 0; e < mesh.num_elements(); ++e)
    for (const auto& p : pairs) {
      const int a = mesh.elements(e, p[0]), b = mesh.elements(e, p[1]);
      const double len = (mesh.nodes.row(a) - mesh.nodes.row(b)).norm() * 0.5 * (scale(a) + scale(b));
      g[a].push_back({b, len});
      g[b].push_back({a, len});
    }
  for (auto& nb : g) {  // each edge appears once per incident tet: dedupe
    std::sort(nb.begin(), nb.end(), [](const Edge& x, const Edge& y) { return x.to < y.to; });
    nb.erase(std::unique(nb.begin(), nb.end(), [](const Edge& x, const Edge& y) { return x.to == y.to; }),
             nb.end());
  }
  return g;
}

/// Lowers `dist` by a Dijkstra sweep from `sources` (only nodes it improves).
void relax_from(const std::vector<std::vector<Edge>>& g, const std::vector<int>& sources, std::vector<double>& dist) {
  using Item = std::pair<double, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> heap;
  for (int s : sources) {
    dist[s] = 0.0;
    heap.push({0.0, s});
  }
  while (!heap.empty()) {
    const auto [d, i] = heap.top();
    heap.pop();
    if (d > dist[i]) continue;
    for (const Edge& e : g[i])
      if (d + e.length < dist[e.to]) {
        dist[e.to] = d + e.length;
        heap.push({dist[e.to], e.to});
      }
  }
}

double point_triangle_distance(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  // Ericson, Real-Time Collision Detection, §5.1.5 (closest point on triangle).
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return (p - a).norm();
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return (p - b).norm();
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return (p - (a + d1 / (d1 - d3) * ab)).norm();
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return (p - c).norm();
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return (p - (a + d2 / (d2 - d6) * ac)).norm();
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return (p - (b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b))).norm();
  const double denom = 1.0 / (va + vb + vc);
  return (p - (a + ab * (vb * denom) + ac * (vc * denom))).norm();
}

/// Distance (m) from p to the union of the tets (0 inside).
double distance_to_mesh(const TetMesh& mesh, const Vec3& p) {
  double best = kInf;
  static const int faces[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  for (int e = 0; e < mesh.num_elements(); ++e) {
    Vec3 x[4];
    for (int a = 0; a < 4; ++a) x[a] = mesh.nodes.row(mesh.elements(e, a)).transpose();
    // Cheap reject: distance to the tet's bounding sphere around its centroid.
    const Vec3 ctr = 0.25 * (x[0] + x[1] + x[2] + x[3]);
    double rad = 0.0;
    for (const Vec3& v : x) rad = std::max(rad, (v - ctr).norm());
    if ((p - ctr).norm() - rad >= best) continue;
    Mat3 D;
    for (int c = 0; c < 3; ++c) D.col(c) = x[c + 1] - x[0];
    const Vec3 l = D.inverse() * (p - x[0]);
    if (l.minCoeff() >= 0.0 && l.sum() <= 1.0) return 0.0;
    for (const auto& f : faces) best = std::min(best, point_triangle_distance(p, x[f[0]], x[f[1]], x[f[2]]));
  }
  return best;
}

void check_roles(const TetMesh& mesh, const VecXi& node_role) {
  require(node_role.size() == mesh.num_nodes(), "handle placement: node_role has ", node_role.size(),
          " entries, expected #N = ", mesh.num_nodes());
}

}  // namespace

VecXi allocate_handles(const VecX& weights, const VecXi& capacity, int K, int min_per_region, double min_fraction) {
  const Eigen::Index R = weights.size();
  require(capacity.size() == R, "handle allocation: ", capacity.size(), " capacities for ", R, " regions");
  require(weights.allFinite() && (R == 0 || weights.minCoeff() >= 0.0),
          "handle allocation: region weights must be finite and non-negative");
  require(R == 0 || capacity.minCoeff() >= 0, "handle allocation: region capacities must be non-negative");
  require(K >= 0 && min_per_region >= 0, "handle allocation: K and the minimum per region must be non-negative");
  const double min_weight = min_fraction * weights.sum();
  VecXi n = VecXi::Zero(R);
  // One handle to the region that wants it most (Sainte-Laguë quotient), among
  // those below `cap(r)`; false when none is.
  auto give_one = [&](auto cap) {
    Eigen::Index best = -1;
    double best_q = -1.0;
    for (Eigen::Index r = 0; r < R; ++r)
      if (n[r] < cap(r)) {
        const double q = weights[r] / (n[r] + 0.5);
        if (q > best_q) best_q = q, best = r;
      }
    if (best < 0) return false;
    ++n[best];
    return true;
  };
  auto up_to_minimum = [&](Eigen::Index r) {
    return weights[r] >= min_weight ? std::min(min_per_region, capacity[r]) : 0;
  };
  int left = K;
  while (left > 0 && give_one(up_to_minimum)) --left;
  while (left > 0 && give_one([&](Eigen::Index r) { return capacity[r]; })) --left;
  return n;
}

VecXi node_regions_from_tets(const TetMesh& mesh, const VecXi& tet_region, int num_regions) {
  require(tet_region.size() == mesh.num_elements(), "node regions: tet_region has ", tet_region.size(),
          " entries, expected #T = ", mesh.num_elements());
  require(num_regions > 0 &&
              (tet_region.size() == 0 || (tet_region.minCoeff() >= 0 && tet_region.maxCoeff() < num_regions)),
          "node regions: tet region labels must lie in [0, ", num_regions, ")");
  const int n = mesh.num_nodes();
  MatX volume = MatX::Zero(n, num_regions);
  const VecX tet_volume = fem::tet_volumes(mesh);
  for (int t = 0; t < mesh.num_elements(); ++t)
    for (int a = 0; a < 4; ++a) volume(mesh.elements(t, a), tet_region[t]) += std::abs(tet_volume[t]);
  VecXi out = VecXi::Constant(n, -1);
  for (int i = 0; i < n; ++i)
    for (int r = 0; r < num_regions; ++r)
      if (volume(i, r) > 0.0 && (out[i] < 0 || volume(i, r) > volume(i, out[i]))) out[i] = r;
  return out;
}

HandleSet select_handles(const TetMesh& mesh, const VecXi& node_role, int K, const VecX& thickness,
                         const VecXi& node_region, const HandlePlacementOptions& options) {
  check_roles(mesh, node_role);
  const int n = mesh.num_nodes();
  VecX t_rel = VecX::Ones(n);  // thickness / mean thickness
  if (thickness.size() > 0) {
    require(thickness.size() == n, "handle placement: thickness has ", thickness.size(), " entries, expected #N = ", n);
    require(thickness.allFinite() && thickness.minCoeff() > 0.0,
            "handle placement: tissue thickness must be finite and positive (m)");
    t_rel = thickness / thickness.mean();
  }
  require(options.dirichlet_distance_scale > 0.0, "handle placement: dirichlet_distance_scale must be positive, got ",
          options.dirichlet_distance_scale);
  std::vector<int> simulated, dirichlet;
  std::vector<char> in_mesh(n, 0);
  for (int e = 0; e < mesh.num_elements(); ++e)
    for (int a = 0; a < 4; ++a) in_mesh[mesh.elements(e, a)] = 1;
  for (int i = 0; i < n; ++i)
    if (node_role(i) != int(NodeRole::Simulated))
      dirichlet.push_back(i);
    else if (in_mesh[i])
      simulated.push_back(i);
  require(K > 0 && K <= int(simulated.size()), "handle placement: asked for ", K, " handles but the mesh has ",
          simulated.size(), " Simulated nodes");

  // Region of each Simulated node (0 when no labels are given).
  VecXi region = VecXi::Zero(n);
  if (node_region.size() > 0) {
    require(node_region.size() == n, "handle placement: node_region has ", node_region.size(),
            " entries, expected #N = ", n);
    for (int i : simulated) {
      require(node_region[i] >= 0, "handle placement: Simulated node ", i, " has no region (label ", node_region[i],
              ")");
      region[i] = node_region[i];
    }
  }
  const int R = 1 + region.maxCoeff();
  const VecX lumped = fem::lumped_mass(mesh);  // m^3 (unit density)
  VecX weight = VecX::Zero(R);
  VecXi capacity = VecXi::Zero(R);
  for (int i : simulated) {
    weight[region[i]] += lumped[i] * std::pow(t_rel[i], options.allocation_thickness_exponent);
    ++capacity[region[i]];
  }
  const VecXi quota = allocate_handles(weight, capacity, K, options.min_per_region, options.min_region_fraction);

  VecX scale(n);
  for (int i = 0; i < n; ++i) scale(i) = std::pow(t_rel(i), options.thickness_exponent);
  const auto graph = edge_graph(mesh, scale);
  std::vector<double> dist(n, kInf);
  if (!dirichlet.empty()) {
    relax_from(graph, dirichlet, dist);
    for (double& d : dist) d *= options.dirichlet_distance_scale;
  }

  HandleSet hs;
  hs.nodes.resize(K);
  VecXi count = VecXi::Zero(R);
  for (int k = 0; k < K; ++k) {
    // The region furthest below its quota (smallest filled fraction).
    int r = -1;
    for (int q = 0; q < R; ++q)
      if (count[q] < quota[q] && (r < 0 || double(count[q]) / quota[q] < double(count[r]) / quota[r])) r = q;
    int pick = -1;
    if (k == 0 && dirichlet.empty()) {
      std::vector<int> candidates;
      for (int i : simulated)
        if (region[i] == r) candidates.push_back(i);
      std::mt19937 rng(options.seed);
      pick = candidates[std::uniform_int_distribution<size_t>(0, candidates.size() - 1)(rng)];
    } else {
      // Farthest Simulated node of region r; unreachable ones (another component) first.
      double best = -1.0;
      for (int i : simulated)
        if (region[i] == r && dist[i] > best) best = dist[i], pick = i;
      require(pick >= 0 && best > 0.0, "handle placement: no Simulated node left for handle ", k, " in region ", r);
    }
    hs.nodes(k) = pick;
    ++count[r];
    relax_from(graph, {pick}, dist);
  }
  hs.positions.resize(K, 3);
  for (int k = 0; k < K; ++k) hs.positions.row(k) = mesh.nodes.row(hs.nodes(k));
  return hs;
}

HandleSet snap_handles(const TetMesh& mesh, const VecXi& node_role, const Points& positions, double tolerance) {
  check_roles(mesh, node_role);
  const int K = int(positions.rows());
  require(K > 0, "handle placement: no handle positions given");
  require(positions.allFinite(), "handle placement: handle positions must be finite");
  HandleSet hs;
  hs.nodes.resize(K);
  std::vector<int> owner(mesh.num_nodes(), -1);
  for (int k = 0; k < K; ++k) {
    const Vec3 p = positions.row(k).transpose();
    const double d = distance_to_mesh(mesh, p);
    require(d <= tolerance, "handle placement: handle ", k, " at (", p.x(), ", ", p.y(), ", ", p.z(), ") lies ", d,
            " m outside the tet mesh, more than the tolerance ", tolerance, " m");
    int best = -1;
    double bd = kInf;
    for (int i = 0; i < mesh.num_nodes(); ++i)
      if (node_role(i) == int(NodeRole::Simulated)) {
        const double di = (mesh.nodes.row(i).transpose() - p).squaredNorm();
        if (di < bd) bd = di, best = i;
      }
    require(best >= 0, "handle placement: the mesh has no Simulated node");
    require(owner[best] < 0, "handle placement: handles ", owner[best], " and ", k, " snap to the same node ", best,
            "; move them apart");
    owner[best] = k;
    hs.nodes(k) = best;
  }
  hs.positions.resize(K, 3);
  for (int k = 0; k < K; ++k) hs.positions.row(k) = mesh.nodes.row(hs.nodes(k));
  return hs;
}

}  // namespace sflsh::basis
