#pragma once
// An elastic block for Hertz indentation tests of the full-FEM contact
// (header-only, like synthetic_avatar.hpp; free to include from any sim test).
//
// Geometry: the box [−W, W] × [−L, 0] × [−W, W] (top face y = 0, the contact
// point at the origin, a node) on a tensor grid graded geometrically away from
// the contact point: along x and z, cells of edge h0 out to |x| = core, then
// each cell `growth` times the previous one out to W (the last cell absorbs
// the rest); along y the same downwards from y = 0 to −L. Each grid box is
// split into 6 positively oriented tets (Kuhn split).
// Roles: the bottom layer (y = −L) is Bone (Dirichlet, u = 0), the rest
// Simulated. Skeleton: all 24 SMPL bones present (FullFem takes 24 world
// transforms), every node and skin vertex weighted 1 on bone 0.
// Skin: the box's boundary triangles (outward), one vertex per boundary node,
// embedded in a tet containing it (barycentric 1 at its corner).
// Material: one isotropic region (young_along = young_through = young_around
// = E), identity tet frames, fung_c = 1e30 Pa so that Ψ is Saint
// Venant–Kirchhoff (the Fung exponent 2Ψ/c vanishes), whose small-strain
// limit is linear elasticity. No reduced basis (W is #N by 0) and no cubature:
// the full FEM needs neither.
#include <algorithm>
#include <array>
#include <map>
#include <vector>

#include "sflsh/asset/avatar.hpp"
#include "sflsh/body/smpl_skeleton.hpp"

namespace sflsh::test {

struct HertzBlockOptions {
  double half_width = 0.2;  ///< W, m
  double depth = 0.2;       ///< L, m
  double h0 = 1.2e-3;       ///< m, cell edge around the contact point
  double core = 7.2e-3;     ///< m, extent (from the contact point, per axis) of the uniform cells
  double growth = 1.6;      ///< ratio of successive cells beyond the core (> 1)
  double young = 1.0e4;     ///< E, Pa
  double poisson = 0.3;     ///< ν
};

/// Node coordinates from 0 to `extent` (> 0): cells of h0 up to `core`, then
/// each `growth` times the previous; the last cell takes the rest (more than
/// half a cell, at most one and a half).
inline std::vector<double> graded_axis(double h0, double core, double growth, double extent) {
  std::vector<double> c{0.0};
  double h = h0;
  while (extent - c.back() > 1.5 * h) {
    c.push_back(c.back() + h);
    if (c.back() >= core - 1e-12) h *= growth;
  }
  c.push_back(extent);
  return c;
}

inline Avatar make_hertz_block(const HertzBlockOptions& o = {}) {
  Avatar a;
  const std::vector<double> half = graded_axis(o.h0, o.core, o.growth, o.half_width);
  std::vector<double> xs;
  for (int i = int(half.size()) - 1; i > 0; --i) xs.push_back(-half[size_t(i)]);
  xs.insert(xs.end(), half.begin(), half.end());
  std::vector<double> ys;
  for (double y : graded_axis(o.h0, o.core, o.growth, o.depth)) ys.push_back(-y);
  std::reverse(ys.begin(), ys.end());  // −L … 0
  const int NX = int(xs.size()), NY = int(ys.size()), NZ = NX;
  auto node_id = [&](int i, int j, int k) { return (j * NZ + k) * NX + i; };
  a.tet.nodes.resize(NX * NY * NZ, 3);
  for (int j = 0; j < NY; ++j)
    for (int k = 0; k < NZ; ++k)
      for (int i = 0; i < NX; ++i) a.tet.nodes.row(node_id(i, j, k)) << xs[size_t(i)], ys[size_t(j)], xs[size_t(k)];

  std::vector<std::array<int, 4>> tets;
  const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (int j = 0; j + 1 < NY; ++j)
    for (int k = 0; k + 1 < NZ; ++k)
      for (int i = 0; i + 1 < NX; ++i)
        for (const auto& p : perms) {
          int c[3] = {i, j, k};
          std::array<int, 4> t;
          t[0] = node_id(c[0], c[1], c[2]);
          for (int s = 0; s < 3; ++s) {
            ++c[p[s]];
            t[size_t(s) + 1] = node_id(c[0], c[1], c[2]);
          }
          const Vec3 x0 = a.tet.nodes.row(t[0]).transpose();
          const double det = (a.tet.nodes.row(t[1]).transpose() - x0)
                                 .dot((a.tet.nodes.row(t[2]).transpose() - x0).cross(a.tet.nodes.row(t[3]).transpose() - x0));
          if (det < 0) std::swap(t[2], t[3]);
          tets.push_back(t);
        }
  const int T = int(tets.size()), N = a.tet.num_nodes();
  a.tet.elements.resize(T, 4);
  for (int t = 0; t < T; ++t)
    for (int c = 0; c < 4; ++c) a.tet.elements(t, c) = tets[size_t(t)][size_t(c)];

  a.parents.assign(kSmplParents.begin(), kSmplParents.end());
  for (const auto& n : kSmplJointNames) a.joint_names.emplace_back(n);
  a.joints_rest = Points::Zero(24, 3);
  a.node_weights = MatXr::Zero(N, 24);
  a.node_weights.col(0).setOnes();
  a.node_role = VecXi::Constant(N, int(NodeRole::Simulated));
  for (int n = 0; n < N; ++n)
    if (a.tet.nodes(n, 1) < -o.depth + 1e-12) a.node_role[n] = int(NodeRole::Bone);

  RegionMaterial m;
  m.name = "block";
  m.young_along = m.young_through = m.young_around = o.young;
  m.poisson = o.poisson;
  m.fung_c = 1e30;
  a.materials = {m};
  a.tet_region = VecXi::Zero(T);
  a.tet_frames = MatXr::Zero(T, 9);
  a.tet_frames.col(0).setOnes();
  a.tet_frames.col(4).setOnes();
  a.tet_frames.col(8).setOnes();
  a.handles = Points::Zero(0, 3);
  a.W.resize(N, 0);

  // Boundary faces (faces of exactly one tet), outward for a positive tet.
  std::map<std::array<int, 3>, std::pair<std::array<int, 3>, int>> faces;  // sorted → (oriented, count)
  const int face_of[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  std::vector<int> node_tet(size_t(N), -1), node_corner(size_t(N), -1);
  for (int t = 0; t < T; ++t) {
    for (int c = 0; c < 4; ++c)
      if (node_tet[size_t(tets[size_t(t)][size_t(c)])] < 0)
        node_tet[size_t(tets[size_t(t)][size_t(c)])] = t, node_corner[size_t(tets[size_t(t)][size_t(c)])] = c;
    for (const auto& f : face_of) {
      std::array<int, 3> oriented = {tets[size_t(t)][size_t(f[0])], tets[size_t(t)][size_t(f[1])],
                                     tets[size_t(t)][size_t(f[2])]},
                         key = oriented;
      std::sort(key.begin(), key.end());
      ++faces.try_emplace(key, oriented, 0).first->second.second;
    }
  }
  std::vector<int> surf_index(size_t(N), -1), surf_nodes;
  std::vector<std::array<int, 3>> tris;
  for (const auto& [key, val] : faces)
    if (val.second == 1) {
      std::array<int, 3> tri;
      for (int c = 0; c < 3; ++c) {
        const int n = val.first[size_t(c)];
        if (surf_index[size_t(n)] < 0) surf_index[size_t(n)] = int(surf_nodes.size()), surf_nodes.push_back(n);
        tri[size_t(c)] = surf_index[size_t(n)];
      }
      tris.push_back(tri);
    }
  const int V = int(surf_nodes.size());
  a.surface_rest.resize(V, 3);
  a.surface_weights = MatXr::Zero(V, 24);
  a.surface_weights.col(0).setOnes();
  a.surface_tet.resize(V);
  a.surface_bary = MatXr::Zero(V, 4);
  a.surface_nodes.resize(V);
  for (int v = 0; v < V; ++v) {
    const int n = surf_nodes[size_t(v)];
    a.surface_rest.row(v) = a.tet.nodes.row(n);
    a.surface_tet[v] = node_tet[size_t(n)];
    a.surface_bary(v, node_corner[size_t(n)]) = 1.0;
    a.surface_nodes[v] = n;
  }
  a.surface_faces.resize(int(tris.size()), 3);
  for (int f = 0; f < int(tris.size()); ++f)
    for (int c = 0; c < 3; ++c) a.surface_faces(f, c) = tris[size_t(f)][size_t(c)];
  a.model_source = "hertz block";
  return a;
}

}  // namespace sflsh::test
