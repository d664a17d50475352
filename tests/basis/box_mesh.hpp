#pragma once
// Test meshes for basis/: a box [0,a]×[0,b]×[0,c] split into nx·ny·nz cubes of
// six positively oriented tets each (Kuhn/Freudenthal split along the main
// diagonal, conforming across cubes).
#include <algorithm>
#include <array>

#include "sflsh/asset/avatar.hpp"
#include "sflsh/mesh/tet_mesh.hpp"

namespace sflsh::test {

inline TetMesh box_tet_mesh(int nx, int ny, int nz, double a, double b, double c) {
  TetMesh m;
  auto id = [&](int i, int j, int k) { return (k * (ny + 1) + j) * (nx + 1) + i; };
  m.nodes.resize((nx + 1) * (ny + 1) * (nz + 1), 3);
  for (int k = 0; k <= nz; ++k)
    for (int j = 0; j <= ny; ++j)
      for (int i = 0; i <= nx; ++i) m.nodes.row(id(i, j, k)) << a * i / nx, b * j / ny, c * k / nz;
  m.elements.resize(6 * nx * ny * nz, 4);
  int e = 0;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        std::array<int, 3> perm = {0, 1, 2};
        do {
          std::array<int, 3> p = {i, j, k};
          int v[4];
          v[0] = id(p[0], p[1], p[2]);
          for (int s = 0; s < 3; ++s) {
            ++p[perm[s]];
            v[s + 1] = id(p[0], p[1], p[2]);
          }
          // Odd permutations give negatively oriented tets: swap two nodes.
          const int inversions = (perm[0] > perm[1]) + (perm[0] > perm[2]) + (perm[1] > perm[2]);
          if (inversions % 2 == 1) std::swap(v[2], v[3]);
          m.elements.row(e++) << v[0], v[1], v[2], v[3];
        } while (std::next_permutation(perm.begin(), perm.end()));
      }
  return m;
}

/// #N NodeRole: Bone on the face y = 0 (a "bone" under the flesh), Simulated elsewhere.
inline VecXi bone_floor_roles(const TetMesh& m) {
  VecXi role = VecXi::Constant(m.num_nodes(), int(NodeRole::Simulated));
  for (int i = 0; i < m.num_nodes(); ++i)
    if (m.nodes(i, 1) < 1e-12) role(i) = int(NodeRole::Bone);
  return role;
}

}  // namespace sflsh::test
