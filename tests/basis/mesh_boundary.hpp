#pragma once
// Brute-force outer-surface nodes of a tet mesh for tests, independent of the
// library: the nodes of the tet faces that belong to exactly one tet.
#include <algorithm>
#include <array>
#include <map>
#include <set>
#include <vector>

#include "sflsh/mesh/tet_mesh.hpp"

namespace sflsh::test {

inline std::vector<int> boundary_nodes(const TetMesh& m) {
  std::map<std::array<int, 3>, int> count;
  static const int faces[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  for (int t = 0; t < m.num_elements(); ++t)
    for (const auto& f : faces) {
      std::array<int, 3> key = {m.elements(t, f[0]), m.elements(t, f[1]), m.elements(t, f[2])};
      std::sort(key.begin(), key.end());
      ++count[key];
    }
  std::set<int> nodes;
  for (const auto& [key, c] : count)
    if (c == 1) nodes.insert(key.begin(), key.end());
  return {nodes.begin(), nodes.end()};
}

}  // namespace sflsh::test
