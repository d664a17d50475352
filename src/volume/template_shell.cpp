// The soft-tissue shell of the template volume: the region between the skin
// and the inner (bone) surface, meshed by Delaunay refinement with a sizing
// field graded towards skinned parts and the bone surface.
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

namespace sflsh::template_internal {

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

/// Depth below the skin (m) over which the sizing field blends from its skin
/// value to its bone-surface value (TemplateOptions::inner_facet_distance).
constexpr double kInnerBlendLength = 0.003;

}  // namespace

/// Meshes the shell between the skin and the inner (bone) surface. The inner
/// surface is the level set  r / (r + D) = inner_depth, with r the distance
/// to the bone segments and D the distance to the skin: the depth fraction
/// of a point along skeleton -> skin, which is 0 on the skeleton and 1 on
/// the skin (in a cylinder around a bone it is exactly |x - axis| / R, so the
/// inner surface is the skin scaled towards the bone). Being a level set of
/// one continuous function, the inner boundary can never self-intersect or
/// cross the skin, also where limbs meet the trunk (crotch, armpits) — an
/// explicitly displaced surface (s + δ(x - s)) can fold there.
ShellMesh mesh_shell(TemplateVolume& tv, const BodyModel& model, const Points& J0, const SurfaceQuery& skin,
                     const VecX& skinned_weight, const TemplateOptions& o) {
  TemplateReport& rep = tv.report;
  const Points& V = model.v_template;
  const Triangles& F = model.faces;
  const int nV = model.num_vertices();
  const Points& S = tv.surface.skeleton_points;
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
  return ShellMesh{std::move(boundary), on_skin_tol};
}

}  // namespace sflsh::template_internal
