#pragma once
// A small synthetic "body" for handle-placement tests: a thick torso block with
// two thin limbs sticking out of its sides, built from the voxels of a box
// mesh (box_mesh.hpp: six Kuhn tets per cube, conforming across cubes).
//
//   voxel h = 0.025 m; torso 12×12×8 voxels (0.30 × 0.30 × 0.20 m) at x ∈ [0.3, 0.6];
//   limbs 12×4×4 voxels (0.30 × 0.10 × 0.10 m) at x ∈ [0, 0.3] and [0.6, 0.9],
//   centred at the torso's mid-height and mid-depth.
// Bone nodes: the torso's vertical centre line and each limb's centre line
// (so the torso's flesh is up to ~0.18 m thick, a limb's 0.05–0.07 m). The
// outermost node layer of each limb (x = 0 and x = 0.9) is Skinned (a "hand").
// Regions (tet labels): 0 torso, 1 left limb, 2 right limb.
#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "box_mesh.hpp"
#include "sflsh/asset/avatar.hpp"

namespace sflsh::test {

struct LimbedBody {
  static constexpr double h = 0.025;
  TetMesh mesh;
  VecXi role;        ///< #N NodeRole
  VecXi tet_region;  ///< #T: 0 torso, 1 left limb, 2 right limb
  VecX thickness;    ///< #N distance to the nearest Bone node (m), at least h/2

  LimbedBody() {
    const int nx = 36, ny = 12, nz = 8;
    const TetMesh box = box_tet_mesh(nx, ny, nz, nx * h, ny * h, nz * h);
    auto cube_region = [&](int i, int j, int k) {
      if (i >= 12 && i < 24) return 0;
      const bool in_limb = j >= 4 && j < 8 && k >= 2 && k < 6;
      return in_limb ? (i < 12 ? 1 : 2) : -1;
    };
    // Keep the tets of the kept cubes (box_tet_mesh: 6 per cube, i fastest).
    std::vector<int> new_id(box.num_nodes(), -1);
    std::vector<std::array<int, 4>> tets;
    std::vector<int> labels;
    for (int t = 0; t < box.num_elements(); ++t) {
      const int c = t / 6, i = c % nx, j = (c / nx) % ny, k = c / (nx * ny);
      const int r = cube_region(i, j, k);
      if (r < 0) continue;
      std::array<int, 4> v;
      for (int a = 0; a < 4; ++a) {
        int& id = new_id[box.elements(t, a)];
        if (id < 0) id = 0;  // mark; numbered below
        v[a] = box.elements(t, a);
      }
      tets.push_back(v);
      labels.push_back(r);
    }
    int n = 0;
    for (int& id : new_id)
      if (id == 0) id = n++;
    mesh.nodes.resize(n, 3);
    for (int i = 0; i < box.num_nodes(); ++i)
      if (new_id[i] >= 0) mesh.nodes.row(new_id[i]) = box.nodes.row(i);
    mesh.elements.resize(int(tets.size()), 4);
    tet_region.resize(int(tets.size()));
    for (size_t t = 0; t < tets.size(); ++t) {
      for (int a = 0; a < 4; ++a) mesh.elements(int(t), a) = new_id[tets[t][a]];
      tet_region[int(t)] = labels[t];
    }
    role = VecXi::Constant(n, int(NodeRole::Simulated));
    auto near = [](double a, double b) { return std::abs(a - b) < 1e-9; };
    const double xc = 18 * h, yc = 6 * h, zc = 4 * h;
    for (int i = 0; i < n; ++i) {
      const double x = mesh.nodes(i, 0), y = mesh.nodes(i, 1), z = mesh.nodes(i, 2);
      const bool torso_axis = near(x, xc) && near(z, zc) && y > 1.5 * h && y < 10.5 * h;
      const bool limb_axis = near(y, yc) && near(z, zc) && (x < 12.5 * h || x > 23.5 * h) && x > 0.5 * h &&
                             x < 35.5 * h;
      if (torso_axis || limb_axis) role[i] = int(NodeRole::Bone);
      if (near(x, 0.0) || near(x, nx * h)) role[i] = int(NodeRole::Skinned);
    }
    thickness.resize(n);
    for (int i = 0; i < n; ++i) {
      double d = 1e9;
      for (int j = 0; j < n; ++j)
        if (role[j] == int(NodeRole::Bone)) d = std::min(d, (mesh.nodes.row(i) - mesh.nodes.row(j)).norm());
      thickness[i] = std::max(d, 0.5 * h);
    }
  }

  /// Region of a point by position (independent of the tet labels): 0 torso, 1/2 limbs.
  static int region_at(double x) { return x < 12 * h - 1e-9 ? 1 : x > 24 * h + 1e-9 ? 2 : 0; }
};

}  // namespace sflsh::test
