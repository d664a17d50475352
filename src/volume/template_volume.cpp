#include "sflsh/volume/template_volume.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <sstream>

#include "sflsh/asset/avatar.hpp"
#include "sflsh/body/body_model_io.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/core/progress.hpp"
#include "sflsh/core/timer.hpp"
#include "sflsh/io/hdf5_file.hpp"
#include "sflsh/io/crash_isolation.hpp"
#include "sflsh/volume/body_regions.hpp"
#include "sflsh/volume/surface_query.hpp"
#include "sflsh/volume/topology_design.hpp"

namespace sflsh {
namespace {

/// Distance from x to the nearest bone segment.
struct SkeletonDistance {
  std::vector<Vec3> a, b;
  double operator()(const Vec3& x) const {
    double best = std::numeric_limits<double>::infinity();
    for (size_t s = 0; s < a.size(); ++s) {
      const double t = closest_segment_parameter(a[s], b[s], x);
      best = std::min(best, (a[s] + t * (b[s] - a[s]) - x).squaredNorm());
    }
    return std::sqrt(best);
  }
};

/// Solves x = s(b) + d (σ(b) - s(b)) for the barycentric point b of triangle
/// (i,j,k) of the skin and the depth d, where s and σ are interpolated
/// linearly over the triangle (the correspondence path field). Gauss–Newton
/// on (u, v, d), b = (1-u-v, u, v). Returns the residual norm.
double solve_path_in_triangle(const Vec3 S[3], const Vec3 X[3], const Vec3& x, Vec3& bary, double& depth) {
  double u = 1.0 / 3, v = 1.0 / 3, d = 0.5;
  double res = std::numeric_limits<double>::infinity();
  for (int it = 0; it < 12; ++it) {
    const Vec3 s = (1 - u - v) * S[0] + u * S[1] + v * S[2];
    const Vec3 g = (1 - u - v) * X[0] + u * X[1] + v * X[2];
    const Vec3 r = s + d * (g - s) - x;
    res = r.norm();
    if (res < 1e-12) break;
    Mat3 Jm;
    Jm.col(0) = (S[1] - S[0]) + d * ((X[1] - S[1]) - (X[0] - S[0]));
    Jm.col(1) = (S[2] - S[0]) + d * ((X[2] - S[2]) - (X[0] - S[0]));
    Jm.col(2) = g - s;
    const Vec3 step = Jm.colPivHouseholderQr().solve(-r);
    if (!step.allFinite()) break;
    u += step[0], v += step[1], d += step[2];
    if (std::abs(u) > 10 || std::abs(v) > 10) break;  // diverging: not this triangle
  }
  bary = Vec3(1 - u - v, u, v);
  depth = d;
  const Vec3 s = bary[0] * S[0] + bary[1] * S[1] + bary[2] * S[2];
  const Vec3 g = bary[0] * X[0] + bary[1] * X[1] + bary[2] * X[2];
  return (s + d * (g - s) - x).norm();
}

/// Depth below the skin (m) over which the sizing field blends from its skin
/// value to its bone-surface value (TemplateOptions::inner_facet_distance).
constexpr double kInnerBlendLength = 0.003;

/// #V sum of each skin vertex's skinning weights on the head/hand/foot joints
/// (is_skinned_joint): >= skinned_weight_threshold means Skinned.
VecX skinned_joint_weight(const BodyModel& model) {
  VecX w = VecX::Zero(model.num_vertices());
  for (int j = 0; j < model.num_joints(); ++j)
    if (is_skinned_joint(j)) w += model.weights.col(j);
  return w;
}

/// The skin -> tet outer boundary distances of TemplateReport (the faces of
/// tv's tet boundary with three skin nodes against the model's template skin).
void measure_skin_fidelity(const TemplateVolume& tv, const BodyModel& model, const VecX& skinned_weight,
                           double skinned_weight_threshold, TemplateReport& rep) {
  const Points& V = model.v_template;
  const Triangles B = tet_boundary_faces(tv.tet);
  std::vector<char> outer(size_t(tv.tet.num_nodes()), 0);
  for (Eigen::Index i = 0; i < tv.outer_nodes.size(); ++i) outer[size_t(tv.outer_nodes[i])] = 1;
  std::vector<std::array<int, 3>> of;
  for (int f = 0; f < B.rows(); ++f)
    if (outer[B(f, 0)] && outer[B(f, 1)] && outer[B(f, 2)]) of.push_back({B(f, 0), B(f, 1), B(f, 2)});
  require(!of.empty(), "template stage: the tet mesh has no boundary on the skin");
  Triangles OF(of.size(), 3);
  for (size_t i = 0; i < of.size(); ++i) OF.row(i) << of[i][0], of[i][1], of[i][2];
  const SurfaceQuery boundary_query(tv.tet.nodes, OF);
  rep.skin_to_outer_boundary = rep.skin_to_outer_boundary_simulated = 0;
  rep.worst_skin_vertex = rep.worst_simulated_skin_vertex = -1;
  for (int v = 0; v < model.num_vertices(); ++v) {
    const double d = boundary_query.distance(V.row(v));
    int dom = 0;
    model.weights.row(v).maxCoeff(&dom);
    if (d > rep.skin_to_outer_boundary)
      rep.skin_to_outer_boundary = d, rep.worst_skin_vertex = v, rep.worst_skin_joint = dom;
    if (skinned_weight[v] < skinned_weight_threshold && d > rep.skin_to_outer_boundary_simulated)
      rep.skin_to_outer_boundary_simulated = d, rep.worst_simulated_skin_vertex = v,
      rep.worst_simulated_skin_joint = dom;
  }
  if (rep.worst_skin_vertex >= 0) rep.worst_skin_position = V.row(rep.worst_skin_vertex).transpose();
  if (rep.worst_simulated_skin_vertex >= 0)
    rep.worst_simulated_skin_position = V.row(rep.worst_simulated_skin_vertex).transpose();
}

}  // namespace

std::string TemplateReport::describe() const {
  std::ostringstream os;
  os << mesh.quality.describe() << "\n"
     << "  nodes: " << num_outer_nodes << " on the skin, " << num_inner_nodes << " on the bone surface, "
     << num_skinned_nodes << " skinned (head/hands/feet)\n"
     << "  skin fidelity: outer nodes within " << outer_node_to_skin * 1e3 << " mm of the skin, skin within "
     << skin_to_outer_boundary * 1e3 << " mm of the tet boundary; path residual max "
     << max_path_residual * 1e3 << " mm\n"
     << "  skin -> boundary max at vertex " << worst_skin_vertex << " (" << worst_skin_position.transpose()
     << ", joint " << worst_skin_joint << "); over simulated skin " << skin_to_outer_boundary_simulated * 1e3
     << " mm at vertex " << worst_simulated_skin_vertex << " (" << worst_simulated_skin_position.transpose()
     << ", joint " << worst_simulated_skin_joint << ")\n"
     << "  time: correspondence " << correspondence_s << " s, meshing " << mesh_s << " s (refine "
     << mesh.refine_s << ", odt " << mesh.odt_s << ", perturb " << mesh.perturb_s << ", exude " << mesh.exude_s
     << "), extension "
     << extension_s << " s, topology design " << topology_s << " s, total " << total_s << " s\n"
     << "  sliver repair: " << sliver_repair.slivers_before << " -> " << sliver_repair.slivers_after
     << " tets below target, min dihedral " << sliver_repair.min_dihedral_before << " -> "
     << sliver_repair.min_dihedral_after << " deg (" << sliver_repair.moves << " node moves)\n  "
     << topology.describe();
  return os.str();
}

TemplateVolume build_template_volume(const BodyModel& model, const TemplateOptions& o) {
  model.validate();
  require(o.inner_depth > 0.05 && o.inner_depth < 0.95, "TemplateOptions::inner_depth = ", o.inner_depth,
          ", expected in (0.05, 0.95)");
  Timer total, timer;
  TemplateVolume tv;
  TemplateReport& rep = tv.report;
  tv.model_hash = body_model_hash(model);
  tv.inner_depth = o.inner_depth;
  const Points& V = model.v_template;
  const Triangles& F = model.faces;
  const int J = model.num_joints(), nV = model.num_vertices();
  const Points J0 = regress_joints(model, V);

  // 1. Surface -> skeleton correspondence (seed §2).
  tv.segments = skeleton_segments(model, V, J0);
  tv.surface = compute_surface_correspondence(model, V, J0, tv.segments, o.correspondence);
  const Points& S = tv.surface.skeleton_points;
  rep.correspondence_s = timer.seconds();
  log_info("template: correspondence of " + std::to_string(nV) + " skin vertices to " +
           std::to_string(tv.segments.size()) + " bone segments");

  // 2. The shell between the skin and the inner (bone) surface. The inner
  // surface is the level set  r / (r + D) = inner_depth, with r the distance
  // to the bone segments and D the distance to the skin: the depth fraction
  // of a point along skeleton -> skin, which is 0 on the skeleton and 1 on
  // the skin (in a cylinder around a bone it is exactly |x - axis| / R, so the
  // inner surface is the skin scaled towards the bone). Being a level set of
  // one continuous function, the inner boundary can never self-intersect or
  // cross the skin, also where limbs meet the trunk (crotch, armpits) — an
  // explicitly displaced surface (s + δ(x - s)) can fold there.
  timer.reset();
  SurfaceQuery skin(V, F);
  SkeletonDistance skel;
  for (const auto& seg : tv.segments) {
    Vec3 a, b;
    segment_endpoints(seg, model.parents, J0, a, b);
    skel.a.push_back(a);
    skel.b.push_back(b);
  }
  const double delta = o.inner_depth;
  const double ratio = (1.0 - delta) / delta;  // in the shell iff D < ratio * r
  // Inside/outside from the pseudo-normal signed distance (one AABB
  // closest-point query per call; ray casting cost twice as much). The skin
  // must be closed and consistently oriented, as SMPL-format bodies are.
  auto in_shell = [&](const Vec3& x) {
    const double sd = skin.signed_distance(x);
    return sd < 0 && -sd < ratio * skel(x);
  };
  // Seed pairs: for a few skin vertices per segment, a point in the shell
  // paired with its skeleton point (inner surface) and with a point just
  // outside the skin (outer surface).
  std::vector<std::vector<int>> per_segment(tv.segments.size());
  for (int v = 0; v < nV; ++v) per_segment[tv.surface.segment[v]].push_back(v);
  std::vector<Vec3> sin, sout;
  for (const auto& vs : per_segment)
    for (int k = 0; k < 4 && !vs.empty(); ++k) {
      const int v = vs[(k * vs.size()) / 4];
      const Vec3 x = V.row(v), s = S.row(v);
      const Vec3 mid = s + 0.5 * (1.0 + delta) * (x - s);
      sin.push_back(mid), sout.push_back(s);
      sin.push_back(mid), sout.push_back(x + 0.02 * (x - s).normalized());
    }
  Points seed_in(sin.size(), 3), seed_out(sout.size(), 3);
  for (size_t i = 0; i < sin.size(); ++i) seed_in.row(i) = sin[i], seed_out.row(i) = sout[i];
  const Vec3 lo = V.colwise().minCoeff().transpose() - Vec3::Constant(0.02);
  const Vec3 hi = V.colwise().maxCoeff().transpose() + Vec3::Constant(0.02);
  // Sizing field: coarser where the nearest skin point is Skinned (those
  // parts only follow skinning), and a looser facet distance on the bone
  // surface (its exact place does not matter, see above). Both blend over a
  // few mm so that Delaunay refinement can grade the mesh.
  require(o.skinned_size_scale > 0, "TemplateOptions::skinned_size_scale = ", o.skinned_size_scale,
          ", expected > 0");
  const VecX skinned_weight = skinned_joint_weight(model);
  auto field = [&skin, &skinned_weight, &F](double skinned_scale, double inner_scale) -> std::function<double(const Vec3&)> {
    if (skinned_scale == 1.0 && inner_scale == 1.0) return {};
    return [&skin, &skinned_weight, &F, skinned_scale, inner_scale](const Vec3& x) {
      int f = 0;
      Vec3 b;
      const Vec3 c = skin.closest_point(x, &f, &b);
      const double w = b[0] * skinned_weight[F(f, 0)] + b[1] * skinned_weight[F(f, 1)] + b[2] * skinned_weight[F(f, 2)];
      const double deep = std::clamp((x - c).norm() / kInnerBlendLength, 0.0, 1.0);
      return (1.0 + (skinned_scale - 1.0) * std::clamp(w, 0.0, 1.0)) * (1.0 + (inner_scale - 1.0) * deep);
    };
  };
  TetrahedralizeOptions mesh_options = o.mesh;
  if (!mesh_options.size_scale) mesh_options.size_scale = field(o.skinned_size_scale, 1.0);
  if (!mesh_options.distance_scale)
    mesh_options.distance_scale = field(std::max(1.0, o.skinned_facet_distance / o.mesh.facet_distance),
                                        std::max(1.0, o.inner_facet_distance / o.mesh.facet_distance));
  log_info("template: meshing the soft-tissue shell (CGAL Mesh_3)");
  tv.tet = tetrahedralize_implicit(in_shell, lo, hi, seed_in, seed_out, mesh_options, &rep.mesh);
  require(rep.mesh.quality.num_inverted == 0, "template stage: ", rep.mesh.quality.num_inverted,
          " inverted/degenerate tets after meshing");
  const int N = tv.tet.num_nodes();
  const Triangles B = tet_boundary_faces(tv.tet);
  std::vector<char> boundary(N, 0);
  for (int f = 0; f < B.rows(); ++f)
    for (int i = 0; i < 3; ++i) boundary[B(f, i)] = 1;
  const double diag = (hi - lo).norm();
  const double on_skin_tol = std::max(1e-5, 100 * o.mesh.relative_error_bound * diag);
  // Slivers left by perturbation/exudation span the thin layer between skin
  // and bone surface (two nodes on each, no interior node to perturb). The
  // bone surface is only "a medium depth" (its exact place does not matter:
  // node depths are measured afterwards), so its nodes and interior nodes
  // may move off the level set to open the slivers; skin nodes stay.
  if (o.sliver_repair.passes > 0) {
    std::vector<char> movable(N, 1);
    for (int n = 0; n < N; ++n)
      if (boundary[n] && skin.distance(tv.tet.nodes.row(n).transpose()) < on_skin_tol) movable[n] = 0;
    rep.sliver_repair = repair_slivers(tv.tet, movable, o.sliver_repair);
    rep.mesh.quality = tet_quality_report(tv.tet, rep.mesh.quality.sliver_threshold_deg);
    require(rep.mesh.quality.num_inverted == 0, "template stage: sliver repair left ",
            rep.mesh.quality.num_inverted, " inverted tets");
  }
  rep.mesh_s = timer.seconds();

  // 3. Boundary nodes: on the skin (to bisection precision) or on the bone surface.
  timer.reset();
  std::vector<char> outer(N, 0);
  std::vector<int> outer_list, inner_list;
  for (int n = 0; n < N; ++n) {
    if (!boundary[n]) continue;
    const double D = skin.distance(tv.tet.nodes.row(n).transpose());
    if (D < on_skin_tol) {
      outer[n] = 1;
      outer_list.push_back(n);
      rep.outer_node_to_skin = std::max(rep.outer_node_to_skin, D);
    } else {
      inner_list.push_back(n);
    }
  }
  tv.outer_nodes = Eigen::Map<VecXi>(outer_list.data(), outer_list.size());
  tv.inner_nodes = Eigen::Map<VecXi>(inner_list.data(), inner_list.size());
  rep.num_outer_nodes = int(outer_list.size());
  rep.num_inner_nodes = int(inner_list.size());
  measure_skin_fidelity(tv, model, skinned_weight, o.skinned_weight_threshold, rep);

  // 4. Node correspondence: find the skin point σ whose path s(σ) -> σ passes
  // through the node (seed §2 "following the correspondence path").
  std::vector<std::vector<int>> vertex_faces(nV);
  for (int f = 0; f < F.rows(); ++f)
    for (int i = 0; i < 3; ++i) vertex_faces[F(f, i)].push_back(f);
  tv.node_face.resize(N);
  tv.node_face_bary.resize(N, 3);
  tv.node_depth.resize(N);
  tv.node_residual.resize(N, 3);
  tv.node_segment.resize(N);
  tv.node_skeleton_coefficients.resize(N, J);
  Progress progress("template: node correspondence", N);
  for (int n = 0; n < N; ++n) {
    if (n % 256 == 0) progress.update(n);
    const Vec3 x = tv.tet.nodes.row(n);
    int face = -1;
    Vec3 bary;
    double depth = 1.0;
    if (outer[n]) {
      skin.closest_point(x, &face, &bary);
    } else {
      // Nearest path segment [s_v, x_v] over all skin vertices ...
      double best = std::numeric_limits<double>::infinity();
      int best_v = 0;
      for (int v = 0; v < nV; ++v) {
        const Vec3 s = S.row(v), g = V.row(v);
        const double t = closest_segment_parameter(s, g, x);
        const double d2 = (s + t * (g - s) - x).squaredNorm();
        if (d2 < best) best = d2, best_v = v;
      }
      // ... then the exact path point in the triangles around that vertex.
      double best_res = std::numeric_limits<double>::infinity();
      for (int f : vertex_faces[best_v]) {
        Vec3 Sf[3], Xf[3];
        for (int i = 0; i < 3; ++i) Sf[i] = S.row(F(f, i)), Xf[i] = V.row(F(f, i));
        Vec3 b;
        double d;
        solve_path_in_triangle(Sf, Xf, x, b, d);
        // Clamp to the triangle and re-project onto its path.
        b = b.cwiseMax(0.0);
        b /= b.sum();
        const Vec3 s = b[0] * Sf[0] + b[1] * Sf[1] + b[2] * Sf[2];
        const Vec3 g = b[0] * Xf[0] + b[1] * Xf[1] + b[2] * Xf[2];
        d = closest_segment_parameter(s, g, x);
        const double res = (s + d * (g - s) - x).norm();
        if (res < best_res) best_res = res, face = f, bary = b, depth = d;
      }
    }
    tv.node_face[n] = face;
    tv.node_face_bary.row(n) = bary.transpose();
    tv.node_depth[n] = depth;
    Eigen::RowVectorXd c = Eigen::RowVectorXd::Zero(J);
    int dom = 0;
    bary.maxCoeff(&dom);
    for (int i = 0; i < 3; ++i) c += bary[i] * tv.surface.coefficients.row(F(face, i));
    tv.node_skeleton_coefficients.row(n) = c;
    tv.node_segment[n] = tv.surface.segment[F(face, dom)];
    const Vec3 s = (c * J0).transpose();
    Vec3 g = Vec3::Zero();
    for (int i = 0; i < 3; ++i) g += bary[i] * V.row(F(face, i)).transpose();
    tv.node_residual.row(n) = (x - (s + depth * (g - s))).transpose();
    rep.max_path_residual = std::max(rep.max_path_residual, tv.node_residual.row(n).norm());
  }
  progress.finish();

  // 5. Extend skinning weights and blend shapes along the paths.
  tv.node_weights.resize(N, J);
  for (int n = 0; n < N; ++n) {
    Eigen::RowVectorXd w = Eigen::RowVectorXd::Zero(J);
    for (int i = 0; i < 3; ++i) w += tv.node_face_bary(n, i) * model.weights.row(F(tv.node_face[n], i));
    tv.node_weights.row(n) = w / w.sum();
  }
  const int nB = model.num_betas();
  tv.node_shapedirs.assign(nB, Points::Zero(N, 3));
  for (int b = 0; b < nB; ++b) {
    const Points dJ = regress_joints(model, model.shapedirs[b]);  // the regressor is linear
    for (int n = 0; n < N; ++n) {
      const Vec3 ds = (tv.node_skeleton_coefficients.row(n) * dJ).transpose();
      Vec3 dg = Vec3::Zero();
      for (int i = 0; i < 3; ++i)
        dg += tv.node_face_bary(n, i) * model.shapedirs[b].row(F(tv.node_face[n], i)).transpose();
      const double d = tv.node_depth[n];
      tv.node_shapedirs[b].row(n) = ((1.0 - d) * ds + d * dg).transpose();
    }
  }
  if (model.has_pose_blend_shapes()) {
    const int P = int(model.posedirs.cols());
    tv.node_posedirs = MatX::Zero(3 * N, P);
    for (int n = 0; n < N; ++n)
      for (int i = 0; i < 3; ++i) {
        const int v = F(tv.node_face[n], i);
        tv.node_posedirs.middleRows(3 * n, 3) +=
            tv.node_depth[n] * tv.node_face_bary(n, i) * model.posedirs.middleRows(3 * v, 3);
      }
  }

  // 6. Roles. Head, hands and feet follow skinning only (seed §2): their nodes
  // are Dirichlet (u = 0) like the bone surface. The soft displacement is one
  // piecewise-linear field over the whole mesh, zero on those nodes, so it
  // fades to zero across the tets that touch them: the simulated and skinned
  // parts share nodes and cannot tear apart.
  tv.node_role = VecXi::Constant(N, int(NodeRole::Simulated));
  for (int n : inner_list) tv.node_role[n] = int(NodeRole::Bone);
  for (int n = 0; n < N; ++n) {
    double w = 0;
    for (int j = 0; j < J; ++j)
      if (is_skinned_joint(j)) w += tv.node_weights(n, j);
    if (w >= o.skinned_weight_threshold) {
      tv.node_role[n] = int(NodeRole::Skinned);
      ++rep.num_skinned_nodes;
    }
  }

  // 7. Regions from the dominant joint of each tet and the way it faces.
  const int T = tv.tet.num_elements();
  tv.tet_region.resize(T);
  for (int t = 0; t < T; ++t) {
    Eigen::RowVectorXd w = Eigen::RowVectorXd::Zero(J);
    Vec3 c = Vec3::Zero(), s = Vec3::Zero();
    for (int i = 0; i < 4; ++i) {
      const int n = tv.tet.elements(t, i);
      w += tv.node_weights.row(n);
      c += tv.tet.nodes.row(n).transpose();
      s += (tv.node_skeleton_coefficients.row(n) * J0).transpose();
    }
    int dom = 0;
    w.maxCoeff(&dom);
    const Vec3 out = c - s;
    const double facing = out.norm() > 0 ? out.normalized().z() : 0.0;
    tv.tet_region[t] = body_region_of(dom, facing, c.y() / 4.0 - J0(dom, 1));
  }
  rep.extension_s = timer.seconds();

  // 8. One connectivity for every shape (seed §4): the repairs the shapes
  // need beyond node moves, made once here (volume/topology_design.hpp).
  // The figures above that depend on the tets are measured again after it.
  timer.reset();
  rep.topology = design_template_topology(tv, model, o.topology);
  if (tv.tet.num_elements() != rep.topology.tets_before || tv.tet.num_nodes() != rep.topology.nodes_before ||
      rep.topology.rounds > 0) {
    rep.mesh.quality = tet_quality_report(tv.tet, rep.mesh.quality.sliver_threshold_deg);
    rep.num_outer_nodes = int(tv.outer_nodes.size());
    rep.num_inner_nodes = int(tv.inner_nodes.size());
    rep.num_skinned_nodes = int((tv.node_role.array() == int(NodeRole::Skinned)).count());
    measure_skin_fidelity(tv, model, skinned_weight, o.skinned_weight_threshold, rep);
  }
  rep.topology_s = timer.seconds();
  rep.total_s = total.seconds();
  return tv;
}

// ---------------------------------------------------------------------------
// Cache file.

void save_template_volume(const TemplateVolume& tv, const std::string& path) {
  io::Hdf5File h5(path, io::Hdf5File::Mode::Write);
  const std::string g = "/template/";
  h5.write_scalar(g + "format_version", std::int64_t(tv.format_version));
  h5.write_string(g + "model_hash", tv.model_hash);
  h5.write_string(g + "units", "metres");
  h5.write_scalar(g + "inner_depth", tv.inner_depth);
  const int nS = int(tv.segments.size());
  Eigen::Matrix<int, Eigen::Dynamic, 2, Eigen::RowMajor> seg(nS, 2);
  VecX ext(nS);
  for (int s = 0; s < nS; ++s) {
    seg(s, 0) = tv.segments[s].joint;
    seg(s, 1) = tv.segments[s].child;
    ext[s] = tv.segments[s].extension;
  }
  h5.write_matrix(g + "segments/joints", seg);
  h5.write_matrix(g + "segments/extension", ext);
  h5.write_matrix(g + "surface/coefficients", tv.surface.coefficients);
  h5.write_matrix(g + "surface/segment", tv.surface.segment);
  h5.write_matrix(g + "surface/skeleton_points", tv.surface.skeleton_points);
  h5.write_matrix(g + "surface/thickness", tv.surface.thickness);
  h5.write_matrix(g + "tet/nodes", tv.tet.nodes);
  h5.write_matrix(g + "tet/elements", tv.tet.elements);
  h5.write_matrix(g + "tet/outer_nodes", tv.outer_nodes);
  h5.write_matrix(g + "tet/inner_nodes", tv.inner_nodes);
  h5.write_matrix(g + "node/face", tv.node_face);
  h5.write_matrix(g + "node/face_bary", tv.node_face_bary);
  h5.write_matrix(g + "node/skeleton_coefficients", tv.node_skeleton_coefficients);
  h5.write_matrix(g + "node/depth", tv.node_depth);
  h5.write_matrix(g + "node/residual", tv.node_residual);
  h5.write_matrix(g + "node/segment", tv.node_segment);
  h5.write_matrix(g + "node/weights", tv.node_weights);
  h5.write_matrix(g + "node/role", tv.node_role);
  h5.write_matrix(g + "tet/region", tv.tet_region);
  const int N = tv.tet.num_nodes(), nB = int(tv.node_shapedirs.size());
  std::vector<double> sd(size_t(nB) * N * 3);
  for (int b = 0; b < nB; ++b) std::copy(tv.node_shapedirs[b].data(), tv.node_shapedirs[b].data() + 3 * N, sd.begin() + size_t(b) * 3 * N);
  h5.write_nd(g + "node/shapedirs", sd.data(), {nB, N, 3});
  if (tv.node_posedirs.size() > 0) h5.write_matrix(g + "node/posedirs", tv.node_posedirs);
  h5.commit();
}

static TemplateVolume load_template_volume_in_this_process(const std::string& path) {
  io::Hdf5File h5(path, io::Hdf5File::Mode::Read);
  const std::string g = "/template/";
  TemplateVolume tv;
  const int version = h5.read_int_scalar(g + "format_version", 0, 1 << 20);
  require(version == kTemplateVolumeFormatVersion, path, ": dataset ", g, "format_version is ", version,
          ", expected ", kTemplateVolumeFormatVersion);
  tv.model_hash = h5.read_string(g + "model_hash");
  tv.inner_depth = h5.read_scalar(g + "inner_depth");
  const auto seg = h5.read_int_matrix(g + "segments/joints", -1, 2);
  const MatXr ext = h5.read_matrix(g + "segments/extension", seg.rows(), 1);
  for (int s = 0; s < seg.rows(); ++s) tv.segments.push_back(BoneSegment{seg(s, 0), seg(s, 1), ext(s, 0)});
  tv.tet.nodes = h5.read_as<Points>(g + "tet/nodes", -1, 3);
  tv.tet.elements = h5.read_int_matrix(g + "tet/elements", -1, 4);
  const int N = tv.tet.num_nodes(), T = tv.tet.num_elements();
  require(N > 0 && T > 0, path, ": dataset ", g, "tet/elements is empty");
  require(tv.tet.elements.minCoeff() >= 0 && tv.tet.elements.maxCoeff() < N, path, ": dataset ", g,
          "tet/elements has node indices outside [0, ", N, ")");
  auto vec_i = [&](const std::string& name, long rows) -> VecXi {
    return h5.read_int_matrix(g + name, rows, 1).col(0);
  };
  tv.surface.coefficients = h5.read_matrix(g + "surface/coefficients");
  const long nV = tv.surface.coefficients.rows(), J = tv.surface.coefficients.cols();
  tv.surface.segment = vec_i("surface/segment", nV);
  tv.surface.skeleton_points = h5.read_as<Points>(g + "surface/skeleton_points", nV, 3);
  tv.surface.thickness = h5.read_matrix(g + "surface/thickness", nV, 1).col(0);
  tv.outer_nodes = vec_i("tet/outer_nodes", -1);
  tv.inner_nodes = vec_i("tet/inner_nodes", -1);
  tv.node_face = vec_i("node/face", N);
  tv.node_face_bary = h5.read_as<Points>(g + "node/face_bary", N, 3);
  tv.node_skeleton_coefficients = h5.read_matrix(g + "node/skeleton_coefficients", N, J);
  tv.node_depth = h5.read_matrix(g + "node/depth", N, 1).col(0);
  tv.node_residual = h5.read_as<Points>(g + "node/residual", N, 3);
  tv.node_segment = vec_i("node/segment", N);
  tv.node_weights = h5.read_matrix(g + "node/weights", N, J);
  tv.node_role = vec_i("node/role", N);
  tv.tet_region = vec_i("tet/region", T);
  std::vector<std::int64_t> shape;
  const std::vector<double> sd = h5.read_nd(g + "node/shapedirs", {-1, N, 3}, &shape);
  tv.node_shapedirs.assign(shape[0], Points(N, 3));
  for (long b = 0; b < shape[0]; ++b) std::copy(sd.begin() + b * 3 * N, sd.begin() + (b + 1) * 3 * N, tv.node_shapedirs[b].data());
  if (h5.has(g + "node/posedirs")) tv.node_posedirs = h5.read_matrix(g + "node/posedirs", 3 * N, -1);
  // Index ranges that later stages rely on.
  auto in_range = [&](const VecXi& v, long hi, const char* name) {
    require(v.size() == 0 || (v.minCoeff() >= 0 && v.maxCoeff() < hi), path, ": dataset ", g, name,
            " has entries outside [0, ", hi, ")");
  };
  in_range(tv.outer_nodes, N, "tet/outer_nodes");
  in_range(tv.inner_nodes, N, "tet/inner_nodes");
  in_range(tv.surface.segment, long(tv.segments.size()), "surface/segment");
  in_range(tv.node_segment, long(tv.segments.size()), "node/segment");
  in_range(tv.tet_region, long(body_region_names().size()), "tet/region");
  in_range(tv.node_role, 3, "node/role");
  for (const auto& s : tv.segments)
    require(s.joint >= 0 && s.joint < J && s.child < J, path, ": dataset ", g, "segments/joints out of range");
  return tv;
}

TemplateVolume load_template_volume(const std::string& path) {
  // A file on which libhdf5 itself crashes is refused, not read (io/crash_isolation.hpp).
  return io::read_in_child_first(path, [&] { return load_template_volume_in_this_process(path); });
}

}  // namespace sflsh
