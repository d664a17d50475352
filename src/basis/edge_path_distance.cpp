#include "basis/edge_path_distance.hpp"

#include <algorithm>
#include <functional>
#include <limits>
#include <queue>
#include <utility>

namespace sflsh::basis {

EdgeGraph::EdgeGraph(const TetMesh& mesh) {
  const int n = mesh.num_nodes();
  std::vector<std::pair<int, int>> edges;
  edges.reserve(size_t(12) * mesh.num_elements());
  for (int e = 0; e < mesh.num_elements(); ++e)
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b)
        if (a != b) edges.emplace_back(mesh.elements(e, a), mesh.elements(e, b));
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  start_.assign(size_t(n) + 1, 0);
  for (const auto& [i, j] : edges) ++start_[size_t(i) + 1];
  for (int i = 0; i < n; ++i) start_[size_t(i) + 1] += start_[size_t(i)];
  neighbour_.reserve(edges.size());
  length_.reserve(edges.size());
  for (const auto& [i, j] : edges) {  // sorted by i: already in CSR order
    neighbour_.push_back(j);
    length_.push_back((mesh.nodes.row(i) - mesh.nodes.row(j)).norm());
  }
}

VecX EdgeGraph::distances(const std::vector<int>& sources, double cutoff) const {
  VecX d = VecX::Constant(num_nodes(), std::numeric_limits<double>::infinity());
  using Item = std::pair<double, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> heap;
  for (int s : sources) {
    d[s] = 0.0;
    heap.emplace(0.0, s);
  }
  while (!heap.empty()) {
    const auto [di, i] = heap.top();
    heap.pop();
    if (di > d[i]) continue;
    for (int p = start_[size_t(i)]; p < start_[size_t(i) + 1]; ++p) {
      const int j = neighbour_[size_t(p)];
      const double dj = di + length_[size_t(p)];
      if (dj <= cutoff && dj < d[j]) {
        d[j] = dj;
        heap.emplace(dj, j);
      }
    }
  }
  return d;
}

}  // namespace sflsh::basis
