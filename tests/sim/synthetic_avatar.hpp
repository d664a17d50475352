#pragma once
// A tiny synthetic Avatar for simulation tests (header-only: only
// tests/sim/*_test.cpp are compiled). Stable API, free to include from any sim test.
//
// Geometry: a box of nx·ny·nz cubes (edge `cell`, metres) standing on y = 0,
// centred on the y axis, each cube split into 6 positively oriented tets
// (Kuhn split along the main diagonal). Skeleton: all 24 SMPL bones present,
// but only the chain pelvis (0) → spine1 (3) → spine2 (6), with joints at
// heights 0, H/3, 2H/3, carries skinning weight (hat functions in y).
// Roles: the bottom layer of nodes (y = 0) is Bone (u = 0); optionally the top
// layer is Skinned (u = 0); the rest is Simulated.
// Basis: handles = 0 → one handle per Simulated node with W = identity on those
// nodes (the "all handles" case, identical to nodal FEM); handles = K > 0 →
// K handles at Simulated nodes (spread evenly by index) with hat weights
// W_nk = max(0, 1 − |x_n − h_k| / handle_radius) on Simulated nodes.
// Cubature: all_tets → elastic = every tet at its barycentre weighted by its
// volume, inertia = every node (unit barycentric in one of its tets) weighted by
// its lumped volume Σ V_e / 4; otherwise `samples` tets spread by index, at an
// off-centre interior point, each weighted by total volume / samples.
// Materials: two regions (x < 0, x ≥ 0) with different moduli; per-tet frames
// rotated about y by a tet-dependent angle (rotated_frames) or identity.
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <vector>

#include <Eigen/Geometry>

#include "sflsh/asset/avatar.hpp"
#include "sflsh/body/smpl_skeleton.hpp"
#include "sflsh/sim/configuration.hpp"
#include "sflsh/sim/energy_term.hpp"

namespace sflsh::test {

struct SyntheticAvatarOptions {
  int nx = 2, ny = 3, nz = 2;    ///< cubes per axis
  double cell = 0.04;            ///< cube edge (m)
  int handles = 0;               ///< 0: W = identity on Simulated nodes; K > 0: K hat handles
  double handle_radius = 0.08;   ///< m, support radius of the hat weights (handles > 0)
  bool skinned_top = false;      ///< top node layer Skinned (u = 0) as well
  bool all_tets = true;          ///< cubature: all tets / all nodes (see above)
  int samples = 0;               ///< samples per cubature when !all_tets
  bool rotated_frames = true;    ///< non-trivial local material frames
  bool two_regions = true;       ///< two materials (x < 0 and x ≥ 0)
};

inline Avatar make_synthetic_avatar(const SyntheticAvatarOptions& o = {}) {
  Avatar a;
  const int NX = o.nx + 1, NY = o.ny + 1, NZ = o.nz + 1;
  const double H = o.ny * o.cell;
  auto node_id = [&](int i, int j, int k) { return (j * NZ + k) * NX + i; };
  a.tet.nodes.resize(NX * NY * NZ, 3);
  for (int j = 0; j < NY; ++j)
    for (int k = 0; k < NZ; ++k)
      for (int i = 0; i < NX; ++i)
        a.tet.nodes.row(node_id(i, j, k)) << (i - 0.5 * o.nx) * o.cell, j * o.cell, (k - 0.5 * o.nz) * o.cell;

  // Kuhn split: one tet per permutation of the axes, a path from corner 000 to 111.
  std::vector<std::array<int, 4>> tets;
  const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (int j = 0; j < o.ny; ++j)
    for (int k = 0; k < o.nz; ++k)
      for (int i = 0; i < o.nx; ++i)
        for (const auto& p : perms) {
          int c[3] = {i, j, k};
          std::array<int, 4> t;
          t[0] = node_id(c[0], c[1], c[2]);
          for (int s = 0; s < 3; ++s) {
            ++c[p[s]];
            t[s + 1] = node_id(c[0], c[1], c[2]);
          }
          const Vec3 x0 = a.tet.nodes.row(t[0]).transpose();
          const double det = (a.tet.nodes.row(t[1]).transpose() - x0)
                                 .dot((a.tet.nodes.row(t[2]).transpose() - x0)
                                          .cross(a.tet.nodes.row(t[3]).transpose() - x0));
          if (det < 0) std::swap(t[2], t[3]);
          tets.push_back(t);
        }
  const int T = int(tets.size()), N = a.tet.num_nodes();
  a.tet.elements.resize(T, 4);
  VecX volume(T);
  for (int t = 0; t < T; ++t) {
    for (int c = 0; c < 4; ++c) a.tet.elements(t, c) = tets[t][c];
    const Vec3 x0 = a.tet.nodes.row(tets[t][0]).transpose();
    volume[t] = (a.tet.nodes.row(tets[t][1]).transpose() - x0)
                    .dot((a.tet.nodes.row(tets[t][2]).transpose() - x0).cross(a.tet.nodes.row(tets[t][3]).transpose() - x0)) /
                6.0;
  }

  // Skeleton: all 24 bones, chain 0 → 3 → 6 along y carries the weight.
  a.parents.assign(kSmplParents.begin(), kSmplParents.end());
  for (const auto& n : kSmplJointNames) a.joint_names.emplace_back(n);
  a.joints_rest = Points::Zero(24, 3);
  for (int j = 0; j < 24; ++j) a.joints_rest.row(j) << 0.01 * j, H, 0.0;
  a.joints_rest.row(0) << 0, 0, 0;
  a.joints_rest.row(3) << 0, H / 3, 0;
  a.joints_rest.row(6) << 0, 2 * H / 3, 0;
  a.node_weights = MatXr::Zero(N, 24);
  for (int n = 0; n < N; ++n) {
    const double s = std::clamp(a.tet.nodes(n, 1) / (H / 3), 0.0, 2.0);  // 0, 1, 2 at the joints
    const double w0 = std::max(0.0, 1 - s), w3 = std::max(0.0, 1 - std::abs(s - 1)), w6 = std::max(0.0, s - 1);
    a.node_weights(n, 0) = w0;
    a.node_weights(n, 3) = w3;
    a.node_weights(n, 6) = w6;
  }

  a.node_role = VecXi::Constant(N, int(NodeRole::Simulated));
  for (int n = 0; n < N; ++n) {
    if (a.tet.nodes(n, 1) < 1e-9) a.node_role[n] = int(NodeRole::Bone);
    if (o.skinned_top && a.tet.nodes(n, 1) > H - 1e-9) a.node_role[n] = int(NodeRole::Skinned);
  }

  // Materials and frames.
  RegionMaterial soft;
  soft.name = "soft";
  RegionMaterial firm = soft;
  firm.name = "firm";
  firm.young_along *= 2;
  firm.young_through *= 1.5;
  firm.young_around *= 3;
  firm.density = 1100;
  a.materials = {soft, firm};
  a.tet_region = VecXi::Zero(T);
  a.tet_frames.resize(T, 9);
  for (int t = 0; t < T; ++t) {
    Vec3 centre = Vec3::Zero();
    for (int c = 0; c < 4; ++c) centre += 0.25 * a.tet.nodes.row(tets[t][c]).transpose();
    if (o.two_regions && centre.x() >= 0) a.tet_region[t] = 1;
    Mat3 R = Mat3::Identity();
    if (o.rotated_frames) R = Eigen::AngleAxisd(0.3 + 0.7 * t, Vec3::UnitY()).toRotationMatrix().transpose();
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) a.tet_frames(t, 3 * r + c) = R(r, c);
  }

  // One incident tet per node, lumped volumes.
  std::vector<int> node_tet(N, -1), node_corner(N, -1);
  VecX lumped = VecX::Zero(N);
  for (int t = 0; t < T; ++t)
    for (int c = 0; c < 4; ++c) {
      lumped[tets[t][c]] += volume[t] / 4;
      if (node_tet[tets[t][c]] < 0) node_tet[tets[t][c]] = t, node_corner[tets[t][c]] = c;
    }

  // Basis.
  std::vector<int> simulated;
  for (int n = 0; n < N; ++n)
    if (a.node_role[n] == int(NodeRole::Simulated)) simulated.push_back(n);
  std::vector<Eigen::Triplet<double>> trip;
  if (o.handles <= 0) {
    a.handles.resize(int(simulated.size()), 3);
    for (int k = 0; k < int(simulated.size()); ++k) {
      a.handles.row(k) = a.tet.nodes.row(simulated[k]);
      trip.emplace_back(simulated[k], k, 1.0);
    }
  } else {
    const int K = std::min<int>(o.handles, int(simulated.size()));
    a.handles.resize(K, 3);
    for (int k = 0; k < K; ++k) a.handles.row(k) = a.tet.nodes.row(simulated[(long(k) * simulated.size()) / K]);
    for (int n : simulated)
      for (int k = 0; k < K; ++k) {
        const double w = 1 - (a.tet.nodes.row(n) - a.handles.row(k)).norm() / o.handle_radius;
        if (w > 0) trip.emplace_back(n, k, w);
      }
  }
  a.W.resize(N, a.handles.rows());
  a.W.setFromTriplets(trip.begin(), trip.end());

  // Cubature.
  auto spread = [&](Cubature& cub, int S, const std::array<double, 4>& bary) {
    cub.elements.resize(S);
    cub.barycentric.resize(S, 4);
    cub.weights = VecX::Constant(S, volume.sum() / S);
    for (int s = 0; s < S; ++s) {
      cub.elements[s] = int((long(s) * T) / S);
      for (int c = 0; c < 4; ++c) cub.barycentric(s, c) = bary[(c + s) % 4];
    }
  };
  if (o.all_tets) {
    a.elastic.elements.resize(T);
    a.elastic.barycentric = MatXr::Constant(T, 4, 0.25);
    a.elastic.weights = volume;
    for (int t = 0; t < T; ++t) a.elastic.elements[t] = t;
    a.inertia.elements.resize(N);
    a.inertia.barycentric = MatXr::Zero(N, 4);
    a.inertia.weights = lumped;
    for (int n = 0; n < N; ++n) {
      a.inertia.elements[n] = node_tet[n];
      a.inertia.barycentric(n, node_corner[n]) = 1.0;
    }
  } else {
    spread(a.elastic, o.samples, {0.25, 0.25, 0.25, 0.25});
    spread(a.inertia, o.samples, {0.1, 0.2, 0.3, 0.4});
  }

  // Surface: boundary faces (faces of exactly one tet), outward oriented.
  std::map<std::array<int, 3>, std::pair<std::array<int, 3>, int>> faces;  // sorted → (oriented, count)
  const int face_of[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};  // outward for a positive tet
  for (int t = 0; t < T; ++t)
    for (const auto& f : face_of) {
      std::array<int, 3> oriented = {tets[t][f[0]], tets[t][f[1]], tets[t][f[2]]}, key = oriented;
      std::sort(key.begin(), key.end());
      auto [it, inserted] = faces.try_emplace(key, oriented, 0);
      ++it->second.second;
    }
  std::vector<int> surf_index(N, -1), surf_nodes;
  std::vector<std::array<int, 3>> tris;
  for (const auto& [key, val] : faces)
    if (val.second == 1) {
      std::array<int, 3> tri;
      for (int c = 0; c < 3; ++c) {
        const int n = val.first[c];
        if (surf_index[n] < 0) surf_index[n] = int(surf_nodes.size()), surf_nodes.push_back(n);
        tri[c] = surf_index[n];
      }
      tris.push_back(tri);
    }
  const int V = int(surf_nodes.size());
  a.surface_rest.resize(V, 3);
  a.surface_weights.resize(V, 24);
  a.surface_tet.resize(V);
  a.surface_bary = MatXr::Zero(V, 4);
  a.surface_nodes.resize(V);
  for (int v = 0; v < V; ++v) {
    const int n = surf_nodes[v];
    a.surface_rest.row(v) = a.tet.nodes.row(n);
    a.surface_weights.row(v) = a.node_weights.row(n);
    a.surface_tet[v] = node_tet[n];
    a.surface_bary(v, node_corner[n]) = 1.0;
    a.surface_nodes[v] = n;
  }
  a.surface_faces.resize(int(tris.size()), 3);
  for (int f = 0; f < int(tris.size()); ++f)
    for (int c = 0; c < 3; ++c) a.surface_faces(f, c) = tris[f][c];
  a.model_source = "synthetic";
  return a;
}

/// Rigid transform rotating by `angle` (rad) about `axis` through `centre`.
inline Isometry rotation_about(const Vec3& centre, const Vec3& axis, double angle) {
  Isometry G = Isometry::Identity();
  G.linear() = Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
  G.translation() = centre - G.linear() * centre;
  return G;
}

/// A prescribed skeleton motion at time t (s): the pelvis bobs vertically
/// (amplitude `lift` m, 2 Hz) and the chain bends about z at spine1 and spine2
/// (amplitude `bend` rad, 1.5 Hz). Bones outside the chain follow their parent.
inline std::vector<Isometry> synthetic_motion(const Avatar& a, double t, double lift = 0.02, double bend = 0.3) {
  const double pi = 3.14159265358979323846;
  std::vector<Isometry> G(24, Isometry::Identity());
  G[0].translation() = Vec3(0, lift * std::sin(2 * pi * 2 * t), 0);
  const double angle = bend * std::sin(2 * pi * 1.5 * t);
  for (int j = 1; j < 24; ++j) {
    const int p = a.parents[j];
    G[j] = G[p];
    if (j == 3 || j == 6)
      G[j] = G[p] * rotation_about(a.joints_rest.row(j).transpose(), Vec3::UnitZ(), angle);
  }
  return G;
}

/// A one-body step context for evaluating single terms of `a`: its soft block
/// (3K) after the bone blocks when `bones_dynamic`, h = 1/60 s.
inline StepContext soft_step_context(const Avatar& a, bool bones_dynamic) {
  StepContext ctx;
  ctx.avatar = &a;
  ctx.layout.bones_dynamic = bones_dynamic;
  ctx.layout.num_reduced = a.num_reduced();
  ctx.h = 1.0 / 60;
  return ctx;
}

}  // namespace sflsh::test
