// The template volume (built once per body model): the soft-tissue tet mesh
// between skin and bones, each node's correspondence path, extended skinning
// weights and blend shapes, roles and regions.
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
#include "sflsh/volume/body_regions.hpp"
#include "sflsh/volume/surface_query.hpp"
#include "sflsh/volume/topology_design.hpp"
#include "volume/template_volume_internal.hpp"

namespace sflsh {
namespace {

using namespace template_internal;

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

/// Extends the skinning weights and blend shapes along the paths.
void extend_along_paths(TemplateVolume& tv, const BodyModel& model) {
  const Triangles& F = model.faces;
  const int J = model.num_joints(), N = tv.tet.num_nodes();
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
}

/// Node roles. Head, hands and feet follow skinning only (seed §2): their nodes
/// are Dirichlet (u = 0) like the bone surface. The soft displacement is one
/// piecewise-linear field over the whole mesh, zero on those nodes, so it
/// fades to zero across the tets that touch them: the simulated and skinned
/// parts share nodes and cannot tear apart.
void assign_roles(TemplateVolume& tv, const std::vector<int>& inner_list, int J, const TemplateOptions& o) {
  TemplateReport& rep = tv.report;
  const int N = tv.tet.num_nodes();
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
}

/// Tet regions from the dominant joint of each tet and the way it faces.
void assign_regions(TemplateVolume& tv, const Points& J0) {
  const int J = int(J0.rows());
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
  rep.correspondence_s = timer.seconds();
  log_info("template: correspondence of " + std::to_string(nV) + " skin vertices to " +
           std::to_string(tv.segments.size()) + " bone segments");

  // 2. The shell between the skin and the inner (bone) surface (mesh_shell).
  timer.reset();
  const SurfaceQuery skin(V, F);
  const VecX skinned_weight = skinned_joint_weight(model);
  const ShellMesh shell = mesh_shell(tv, model, J0, skin, skinned_weight, o);
  const int N = tv.tet.num_nodes();
  rep.mesh_s = timer.seconds();

  // 3. Boundary nodes: on the skin (to bisection precision) or on the bone surface.
  timer.reset();
  std::vector<char> outer(N, 0);
  std::vector<int> outer_list, inner_list;
  for (int n = 0; n < N; ++n) {
    if (!shell.boundary[n]) continue;
    const double D = skin.distance(tv.tet.nodes.row(n).transpose());
    if (D < shell.on_skin_tol) {
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

  // 4. Node correspondence (correspond_nodes), 5. the skinning weights and
  // blend shapes extended along the paths, 6. roles, 7. regions.
  correspond_nodes(tv, model, J0, skin, outer);
  extend_along_paths(tv, model);
  assign_roles(tv, inner_list, J, o);
  assign_regions(tv, J0);
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

}  // namespace sflsh
