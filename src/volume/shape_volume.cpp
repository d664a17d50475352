#include "sflsh/volume/shape_volume.hpp"

#include <algorithm>
#include <sstream>

#include "sflsh/body/body_model_io.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/core/timer.hpp"
#include "sflsh/meshing/surface_checks.hpp"
#include "sflsh/volume/body_regions.hpp"
#include "sflsh/volume/point_embedding.hpp"
#include "sflsh/volume/surface_query.hpp"

namespace sflsh {

std::string ShapeReport::describe() const {
  std::ostringstream os;
  os << quality.describe() << "\n  skin embedding: " << num_embedded_outside
     << " skin vertices outside the tet mesh, farthest " << max_embedding_distance * 1e3 << " mm; shape stage "
     << seconds << " s";
  if (num_relaxed_nodes > 0) os << "; thickness scale relaxed at " << num_relaxed_nodes << " nodes";
  if (untangled_nodes > 0) os << "; displacement made harmonic at " << untangled_nodes << " folded nodes";
  if (smoothing.passes > 0)
    os << "\n  interior optimization: min dihedral " << smoothing.min_dihedral_before << " -> "
       << smoothing.min_dihedral_after << " deg, tets below " << smoothing.below_target_before << " -> "
       << smoothing.below_target_after << " (target), " << smoothing.nodes_moved << " nodes moved (max "
       << smoothing.max_displacement * 1e3 << " mm) in " << smoothing.passes << " passes";
  if (skin_smoothing.passes > 0)
    os << "; with skin nodes sliding on the skin: min dihedral " << skin_smoothing.min_dihedral_after << " deg, "
       << skin_smoothing.below_target_after << " tets below target, " << skin_smoothing.nodes_moved
       << " nodes moved (max " << skin_smoothing.max_displacement * 1e3 << " mm)";
  if (wide_skin_smoothing.passes > 0)
    os << "; sliding further: min dihedral " << wide_skin_smoothing.min_dihedral_after << " deg, "
       << wide_skin_smoothing.nodes_moved << " nodes moved";
  if (skin_self_intersects == 1)
    os << "\n  the shaped skin self-intersects (the body model gives no valid solid at these betas)";
  return os.str();
}

namespace {

// Per-node thickness scale: the mean of the region scales of the incident
// tets, then Jacobi-smoothed over the tet graph so the layer thickness varies
// smoothly across region borders (a step would shear the tets there).
VecX node_thickness_scale(const TemplateVolume& tv, const ThicknessMap& map, int iterations) {
  const auto& names = body_region_names();
  const int N = tv.tet.num_nodes(), T = tv.tet.num_elements();
  VecX sum = VecX::Zero(N), cnt = VecX::Zero(N);
  for (int t = 0; t < T; ++t) {
    const double s = map.scale_of(names[tv.tet_region[t]]);
    for (int i = 0; i < 4; ++i) sum[tv.tet.elements(t, i)] += s, cnt[tv.tet.elements(t, i)] += 1;
  }
  VecX k = sum.cwiseQuotient(cnt.cwiseMax(1.0));
  const auto nbr = tet_node_neighbours(tv.tet);
  for (int it = 0; it < iterations; ++it) {
    VecX next(N);
    for (int n = 0; n < N; ++n) {
      double m = 0;
      for (int u : nbr[n]) m += k[u];
      next[n] = nbr[n].empty() ? k[n] : 0.5 * k[n] + 0.5 * m / nbr[n].size();
    }
    k.swap(next);
  }
  return k;
}

/// The ends of each node's path: skeleton point s and skin point g, at β = 0
/// (s0, g0; to carry the residual along) and at β (sb, gb).
struct NodePaths {
  Points s0, g0, sb, gb;
};

NodePaths node_paths(const TemplateVolume& tv, const BodyModel& model, const Points& v_shaped, const Points& joints) {
  const int N = tv.tet.num_nodes();
  const Triangles& F = model.faces;
  const Points J0 = regress_joints(model, model.v_template);
  NodePaths p;
  Points &s0 = p.s0, &g0 = p.g0, &sb = p.sb, &gb = p.gb;
  s0.resize(N, 3), g0.resize(N, 3), sb.resize(N, 3), gb.resize(N, 3);
  for (int n = 0; n < N; ++n) {
    s0.row(n) = tv.node_skeleton_coefficients.row(n) * J0;
    sb.row(n) = tv.node_skeleton_coefficients.row(n) * joints;
    Vec3 a = Vec3::Zero(), b = Vec3::Zero();
    for (int i = 0; i < 3; ++i) {
      const int v = F(tv.node_face[n], i);
      a += tv.node_face_bary(n, i) * model.v_template.row(v).transpose();
      b += tv.node_face_bary(n, i) * v_shaped.row(v).transpose();
    }
    g0.row(n) = a.transpose();
    gb.row(n) = b.transpose();
  }
  return p;
}

/// The residual (the part of the node the path fit does not explain, up to
/// ~1 cm where paths fan out) rides in the frame of the path: rotated with
/// it and scaled by its length change. A constant residual would not scale
/// with the body, and a uniform scale (procedural β0) would then shear and
/// invert slivers; in the path frame a uniformly scaled body gives exactly
/// the uniformly scaled mesh.
Points path_frame_residual(const TemplateVolume& tv, const NodePaths& paths) {
  const int N = tv.tet.num_nodes();
  const Points &s0 = paths.s0, &g0 = paths.g0, &sb = paths.sb, &gb = paths.gb;
  Points residual(N, 3);
  for (int n = 0; n < N; ++n) {
    const Vec3 p0 = g0.row(n) - s0.row(n), pb = gb.row(n) - sb.row(n);
    const Vec3 r0 = tv.node_residual.row(n).transpose();
    if (p0.norm() < 1e-6 || pb.norm() < 1e-6) {
      residual.row(n) = r0.transpose();
      continue;
    }
    const Eigen::Quaterniond q = Eigen::Quaterniond::FromTwoVectors(p0, pb);
    residual.row(n) = (pb.norm() / p0.norm() * (q * r0)).transpose();
  }
  return residual;
}

/// Places the nodes of `mesh` for a per-node thickness scale k (depth d' = 1 - k (1 - d)).
void place_nodes(const TemplateVolume& tv, const NodePaths& paths, const Points& residual, const VecX& k,
                 TetMesh& mesh, VecX& node_depth) {
  const int N = tv.tet.num_nodes();
  for (int n = 0; n < N; ++n) {
    const double d = 1.0 - k[n] * (1.0 - tv.node_depth[n]);
    node_depth[n] = d;
    mesh.nodes.row(n) = paths.sb.row(n) + d * (paths.gb.row(n) - paths.sb.row(n)) + residual.row(n);
  }
}

/// Marks the nodes within `rings` edges of a marked node (`extend(u)`: whether u may join).
template <class Extend>
void grow_marks(std::vector<char>& mark, const std::vector<std::vector<int>>& nbr, int rings, Extend extend) {
  for (int ring = 0; ring < rings; ++ring) {
    std::vector<char> next = mark;
    for (size_t n = 0; n < mark.size(); ++n)
      if (mark[n])
        for (int u : nbr[n]) next[u] = next[u] || extend(u);
    mark.swap(next);
  }
}

/// Where converging paths (crotch, armpits, between fingers) make the
/// thickened layer fold or flatten, the thickness scale is relaxed towards 1
/// around the offending tets (halving the change per round, over a 2-ring
/// so the relaxation itself varies smoothly). A tet offends if it is
/// inverted or its smallest dihedral angle falls below both its own at
/// k = 1 and min_dihedral_deg: the thickness map never makes a tet worse
/// than that.
/// Leaves `mesh` and out.node_depth placed at the relaxed scale out.node_thickness_scale.
void relax_thickness_scale(const TemplateVolume& tv, const NodePaths& paths, const Points& residual,
                           const std::vector<std::vector<int>>& nbr, const ShapeOptions& o, TetMesh& mesh,
                           ShapedNodes& out) {
  const int N = tv.tet.num_nodes();
  const VecX k_target = out.node_thickness_scale;
  place_nodes(tv, paths, residual, VecX::Ones(N), mesh, out.node_depth);
  std::vector<double> floor_deg(tv.tet.num_elements());
  for (int t = 0; t < tv.tet.num_elements(); ++t)
    floor_deg[t] = std::min(o.min_dihedral_deg, tet_quality(mesh, t).min_dihedral_deg);
  VecX relax = VecX::Ones(N);
  for (int round = 0;; ++round) {
    out.node_thickness_scale = (k_target.array() - 1.0) * relax.array() + 1.0;
    place_nodes(tv, paths, residual, out.node_thickness_scale, mesh, out.node_depth);
    std::vector<int> bad;
    for (int t = 0; t < tv.tet.num_elements(); ++t)
      if (const TetQuality q = tet_quality(mesh, t); q.signed_volume <= 0 || q.min_dihedral_deg < floor_deg[t] - 1e-9)
        bad.push_back(t);
    if (bad.empty() || round >= o.max_relax_rounds) break;
    std::vector<char> mark(N, 0);
    for (int t : bad)
      for (int i = 0; i < 4; ++i) mark[tv.tet.elements(t, i)] = 1;
    grow_marks(mark, nbr, 2, [](int) { return true; });
    const bool last = round + 1 >= o.max_relax_rounds;
    for (int n = 0; n < N; ++n)
      if (mark[n]) relax[n] = last ? 0.0 : 0.5 * relax[n];
  }
  for (int n = 0; n < N; ++n) out.report.num_relaxed_nodes += relax[n] < 1.0;
}

/// Untangling where the node paths fold (a shape that shortens a limb by
/// decimetres crowds the paths of the calf or thigh so that bone-surface
/// nodes overtake skin nodes): around the inverted tets that have a node off
/// the skin, the displacement from the template of the nodes off the skin is
/// replaced by its harmonic extension from the surrounding nodes (Jacobi
/// sweeps of the graph Laplacian; the skin and the nodes outside the region
/// stay). A smooth displacement of the template, which is good, keeps the
/// tets' shape; the region grows each round until nothing folds.
/// Returns the number of node moves.
int untangle_folds(const TemplateVolume& tv, const std::vector<char>& on_skin,
                   const std::vector<std::vector<int>>& nbr, const ShapeOptions& o, TetMesh& mesh) {
  const int N = tv.tet.num_nodes();
  int untangled = 0;
  for (int round = 0; o.smoothing.passes > 0 && round < o.untangle_rounds; ++round) {
    std::vector<char> region(N, 0);
    int folded = 0;
    for (int t = 0; t < tv.tet.num_elements(); ++t) {
      if (tet_quality(mesh, t).signed_volume > 0) continue;
      bool off_skin = false;
      for (int i = 0; i < 4; ++i) off_skin = off_skin || !on_skin[tv.tet.elements(t, i)];
      if (!off_skin) continue;
      ++folded;
      for (int i = 0; i < 4; ++i) region[tv.tet.elements(t, i)] = !on_skin[tv.tet.elements(t, i)];
    }
    if (folded == 0) break;
    grow_marks(region, nbr, 2 * (round + 1), [&](int u) { return !on_skin[u]; });
    Points u = mesh.nodes - tv.tet.nodes;
    std::vector<int> ids;
    for (int n = 0; n < N; ++n)
      if (region[n]) ids.push_back(n);
    for (int it = 0; it < 200; ++it) {
      Points next = u;
      for (int n : ids) {
        Vec3 m = Vec3::Zero();
        for (int w : nbr[n]) m += u.row(w).transpose();
        next.row(n) = (m / double(nbr[n].size())).transpose();
      }
      u.swap(next);
    }
    for (int n : ids) mesh.nodes.row(n) = tv.tet.nodes.row(n) + u.row(n);
    untangled += int(ids.size());
  }
  return untangled;
}

/// Interior optimization: the thickness map (and a shape that stretches the
/// layer unevenly) flattens some tets of the thin shell, where nearly every
/// tet joins skin nodes to bone-surface nodes; the skin stays, the
/// bone-surface nodes slide across their paths (their depth along the path
/// is kept to first order), interior nodes move freely.
/// The floor is quality_floor_deg even where the template is below it (its
/// skin-only tets, which the template stage cannot move): the skin nodes
/// slide along the skin below.
void optimize_interior(const TemplateVolume& tv, const NodePaths& paths, const std::vector<char>& on_skin,
                       const Points& v_shaped, const Triangles& F, const ShapeOptions& o, TetMesh& mesh,
                       ShapeReport& report) {
  const int N = tv.tet.num_nodes();
  const double quality_floor = o.quality_floor_deg;
  if (o.smoothing.passes > 0 && tet_quality_report(mesh).min_dihedral_deg < quality_floor) {
    std::vector<NodeFreedom> freedom(N, NodeFreedom::Free);
    Points normals = Points::Zero(N, 3);
    for (int i = 0; i < tv.inner_nodes.size(); ++i) {
      const int n = tv.inner_nodes[i];
      const Vec3 path = paths.gb.row(n) - paths.sb.row(n);
      if (path.norm() > 1e-9) {
        freedom[n] = NodeFreedom::Slide;
        normals.row(n) = path.normalized().transpose();
      } else {
        freedom[n] = NodeFreedom::Fixed;
      }
    }
    for (int n = 0; n < N; ++n)
      if (on_skin[n]) freedom[n] = NodeFreedom::Fixed;
    report.smoothing = smooth_interior_nodes(mesh, freedom, normals, o.smoothing);
    // Skin nodes of the tets still below the floor slide along the shaped skin
    // (each candidate projected onto it), first at most skin_slide_fraction of
    // their shortest edge, then (what is left are mostly ears of the skin: a
    // skin node in a single tet, which only moving along the skin can raise)
    // final_skin_slide_fraction.
    const SurfaceQuery skin(v_shaped, F);
    auto slide_skin_of_bad_tets = [&](double reach) {
      for (int t = 0; t < mesh.num_elements(); ++t)
        if (tet_quality(mesh, t).min_dihedral_deg < quality_floor)
          for (int i = 0; i < 4; ++i)
            if (on_skin[mesh.elements(t, i)]) freedom[mesh.elements(t, i)] = NodeFreedom::Surface;
      InteriorSmoothingOptions so = o.smoothing;
      so.max_displacement_fraction = reach;
      return smooth_interior_nodes(mesh, freedom, normals, so, [&](const Vec3& y) { return skin.closest_point(y); });
    };
    if (o.skin_slide_fraction > 0 && report.smoothing.min_dihedral_after < quality_floor)
      report.skin_smoothing = slide_skin_of_bad_tets(o.skin_slide_fraction);
    if (o.final_skin_slide_fraction > 0 && tet_quality_report(mesh).min_dihedral_deg < quality_floor)
      report.wide_skin_smoothing = slide_skin_of_bad_tets(o.final_skin_slide_fraction);
  }
}

}  // namespace

ShapedNodes place_shape_nodes(const TemplateVolume& tv, const BodyModel& model, const VecX& betas,
                              const ThicknessMap& thickness, const ShapeOptions& o) {
  Timer timer;
  const std::string hash = body_model_hash(model);
  require(hash == tv.model_hash, "shape_volume: the template volume was built for body model ", tv.model_hash,
          " but the model given (", model.source, ") has hash ", hash);
  const int N = tv.tet.num_nodes();
  const Triangles& F = model.faces;
  require(tv.node_face.size() == N && tv.node_face.maxCoeff() < F.rows(),
          "shape_volume: template node faces do not match the model's ", F.rows(), " faces");

  ShapedNodes out;
  out.v_shaped = shape_vertices(model, betas);
  out.joints = regress_joints(model, out.v_shaped);
  const Points& v_shaped = out.v_shaped;
  const Points& joints = out.joints;
  TetMesh mesh;  // the template's connectivity, never changed here

  // Thickness scale k per node; the depth d' = 1 - k (1 - d) keeps the skin
  // (d = 1) fixed and scales the soft layer. Thickening is capped per node
  // so that d' >= min_depth (the layer never reaches past the skeleton
  // point); nodes already deeper than that keep k <= 1. A global cap would
  // let the few nodes whose path fit ends at the skeleton (d = 0, near
  // joints) shrink the layer of the whole body.
  out.node_thickness_scale = node_thickness_scale(tv, thickness, o.scale_smoothing_iterations);
  for (int n = 0; n < N; ++n) {
    const double cap = std::max(1.0, (1.0 - o.min_depth) / std::max(1e-9, 1.0 - tv.node_depth[n]));
    out.node_thickness_scale[n] = std::min(out.node_thickness_scale[n], cap);
  }

  // Path end points per node at β = 0 (to carry the residual along) and at β;
  // the residual in the path's frame (path_frame_residual).
  const NodePaths paths = node_paths(tv, model, v_shaped, joints);
  const Points residual = path_frame_residual(tv, paths);
  mesh.elements = tv.tet.elements;
  mesh.nodes.resize(N, 3);
  out.node_depth.resize(N);
  const std::vector<std::vector<int>> nbr = tet_node_neighbours(tv.tet);
  relax_thickness_scale(tv, paths, residual, nbr, o, mesh, out);

  std::vector<char> on_skin(N, 0);
  for (int i = 0; i < tv.outer_nodes.size(); ++i) on_skin[tv.outer_nodes[i]] = 1;
  out.report.untangled_nodes += untangle_folds(tv, on_skin, nbr, o, mesh);
  optimize_interior(tv, paths, on_skin, v_shaped, F, o, mesh, out.report);
  out.report.quality = tet_quality_report(mesh);
  out.nodes = std::move(mesh.nodes);
  out.node_skeleton = paths.sb;
  out.report.seconds = timer.seconds();
  return out;
}

ShapedVolume shape_volume(const TemplateVolume& tv, const BodyModel& model, const VecX& betas,
                          const ThicknessMap& thickness, const ShapeOptions& o) {
  Timer timer;
  ShapedNodes placed = place_shape_nodes(tv, model, betas, thickness, o);
  ShapedVolume out;
  out.report = placed.report;
  out.node_depth = std::move(placed.node_depth);
  out.node_thickness_scale = std::move(placed.node_thickness_scale);
  const Points& v_shaped = placed.v_shaped;
  const Points& joints = placed.joints;
  const Triangles& F = model.faces;
  Avatar& av = out.avatar;
  av.tet.nodes = std::move(placed.nodes);
  av.tet.elements = tv.tet.elements;  // one connectivity for every shape (seed §4)
  av.tet_region = tv.tet_region;
  if (out.report.quality.num_inverted > 0 || out.report.quality.min_dihedral_deg < o.quality_floor_deg)
    out.report.skin_self_intersects = check_surface(v_shaped, F, true).self_intersects ? 1 : 0;
  require(out.report.quality.num_inverted == 0, "shape_volume: ",
          out.report.skin_self_intersects == 1
              ? "the shaped skin self-intersects at these betas (the body model gives no valid solid there, so "
                "no tet mesh bounded by it exists); "
              : "",
          out.report.quality.num_inverted, " tets inverted for this shape (smallest volume ",
          out.report.quality.min_volume, " m^3) even with the thickness map relaxed to 1 around them; reduce |betas|");

  // Meta, skeleton, skin.
  av.betas = betas;
  av.model_hash = tv.model_hash;
  av.model_source = model.source;
  av.joints_rest = joints;
  av.parents = model.parents;
  av.joint_names = model.joint_names;
  av.surface_rest = v_shaped;
  av.surface_faces = F;
  av.surface_weights = model.weights;
  if (model.has_pose_blend_shapes()) av.surface_posedirs = model.posedirs;
  const PointEmbedding emb = embed_points(av.tet, v_shaped);
  av.surface_tet = emb.tet;
  av.surface_bary = emb.bary;
  out.report.max_embedding_distance = emb.distance.maxCoeff();
  out.report.num_embedded_outside = emb.num_outside;

  // Volume fields: the template's per-node fields.
  av.node_weights = tv.node_weights;
  av.node_role = tv.node_role;
  av.surface_nodes = tv.outer_nodes;
  av.materials = default_region_materials();
  av.tet_frames = tet_frames(av.tet, placed.node_skeleton, tv.node_segment, tv.segments, model.parents, joints);
  av.capsules = fit_bone_capsules(av.tet.nodes, placed.node_skeleton, tv.outer_nodes, tv.node_segment, tv.segments,
                                  model.parents, joints, o.capsule_percentile);
  out.report.seconds = timer.seconds();
  return out;
}

}  // namespace sflsh
