#include "sflsh/meshing/tetrahedralize.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Labeled_mesh_domain_3.h>
#include <CGAL/Mesh_complex_3_in_triangulation_3.h>
#include <CGAL/Mesh_criteria_3.h>
#include <CGAL/Mesh_error_code.h>
#include <CGAL/Mesh_triangulation_3.h>
#include <CGAL/Random.h>
#include <CGAL/exude_mesh_3.h>
#include <CGAL/odt_optimize_mesh_3.h>
#include <CGAL/Mesh_3/Sliver_perturber.h>
#include <CGAL/Mesh_3/sliver_criteria.h>
#include <CGAL/Mesh_3/vertex_perturbation.h>
#include <CGAL/refine_mesh_3.h>

#include <algorithm>
#include <array>
#include <cfloat>
#include <map>
#include <unordered_map>
#include <vector>

#include "sflsh/core/error.hpp"
#include "sflsh/core/timer.hpp"

namespace sflsh {
namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using LabelFunction = std::function<int(const K::Point_3&)>;
using Domain = CGAL::Labeled_mesh_domain_3<K>;
using Tr = CGAL::Mesh_triangulation_3<Domain, CGAL::Default, CGAL::Sequential_tag>::type;
using C3t3 = CGAL::Mesh_complex_3_in_triangulation_3<Tr>;
using Criteria = CGAL::Mesh_criteria_3<Tr>;

// Faces of tet (a,b,c,d) opposite each node, oriented outwards for a
// positively oriented tet (see tet_quality.cpp).
constexpr int kFace[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};

using FaceKey = std::array<int, 3>;
FaceKey sorted_face(int a, int b, int c) {
  FaceKey k{a, b, c};
  std::sort(k.begin(), k.end());
  return k;
}

// Number of tets sharing each face.
std::map<FaceKey, int> face_counts(const Tets& T) {
  std::map<FaceKey, int> count;
  for (int t = 0; t < T.rows(); ++t)
    for (const auto& f : kFace) ++count[sorted_face(T(t, f[0]), T(t, f[1]), T(t, f[2]))];
  return count;
}

// Removes flat boundary caps: tets below `threshold_deg` with >= 2 faces on the
// boundary and all 4 nodes on the boundary. Such a tet spans a nearly planar
// patch of the boundary; dropping it exposes its other faces, whose nodes all
// lie on the boundary already, so the boundary stays a surface through
// boundary points. Repeats while it finds any. Returns how many were removed.
int remove_boundary_slivers(TetMesh& mesh, double threshold_deg) {
  int removed = 0;
  for (int pass = 0; pass < 10; ++pass) {
    const auto count = face_counts(mesh.elements);
    std::vector<char> on_boundary(mesh.num_nodes(), 0);
    for (int t = 0; t < mesh.num_elements(); ++t)
      for (const auto& f : kFace) {
        const auto& e = mesh.elements;
        if (count.at(sorted_face(e(t, f[0]), e(t, f[1]), e(t, f[2]))) == 1)
          for (int i : f) on_boundary[e(t, i)] = 1;
      }
    std::vector<int> keep;
    keep.reserve(mesh.num_elements());
    int removed_now = 0;
    for (int t = 0; t < mesh.num_elements(); ++t) {
      const auto& e = mesh.elements;
      int boundary_faces = 0;
      for (const auto& f : kFace)
        boundary_faces += count.at(sorted_face(e(t, f[0]), e(t, f[1]), e(t, f[2]))) == 1;
      const bool all_nodes = on_boundary[e(t, 0)] && on_boundary[e(t, 1)] && on_boundary[e(t, 2)] &&
                             on_boundary[e(t, 3)];
      if (boundary_faces >= 2 && all_nodes && tet_quality(mesh, t).min_dihedral_deg < threshold_deg) {
        ++removed_now;
      } else {
        keep.push_back(t);
      }
    }
    if (removed_now == 0) break;
    Tets kept(keep.size(), 4);
    for (size_t i = 0; i < keep.size(); ++i) kept.row(i) = mesh.elements.row(keep[i]);
    mesh.elements = kept;
    removed += removed_now;
  }
  return removed;
}

// Drops nodes no tet uses and renumbers (keeps the original order).
void compact_nodes(TetMesh& mesh) {
  std::vector<int> map(mesh.num_nodes(), -1);
  for (int t = 0; t < mesh.num_elements(); ++t)
    for (int i = 0; i < 4; ++i) map[mesh.elements(t, i)] = 0;
  int n = 0;
  for (int& m : map)
    if (m == 0) m = n++;
  Points nodes(n, 3);
  for (int i = 0; i < mesh.num_nodes(); ++i)
    if (map[i] >= 0) nodes.row(map[i]) = mesh.nodes.row(i);
  for (int t = 0; t < mesh.num_elements(); ++t)
    for (int i = 0; i < 4; ++i) mesh.elements(t, i) = map[mesh.elements(t, i)];
  mesh.nodes = nodes;
}

// A Mesh_3 sizing field (signature FT(Point_3, dimension, index)): `base`
// times the user's factor at the point.
struct ScaledField {
  double base;
  const std::function<double(const Vec3&)>* scale;
  K::FT operator()(const K::Point_3& p, int, const Domain::Index&) const {
    return base * (*scale)(Vec3(p.x(), p.y(), p.z()));
  }
};

/// Mesh_3 criteria: uniform unless a sizing field is given (CGAL picks the
/// variable-size criterion from the argument type). `one` (the unit field)
/// must outlive the criteria.
Criteria mesh_criteria(const TetrahedralizeOptions& o, const std::function<double(const Vec3&)>& one) {
  namespace p = CGAL::parameters;
  const auto* size_scale = o.size_scale ? &o.size_scale : &one;
  const auto* distance_scale = o.distance_scale ? &o.distance_scale : &one;
  return (o.size_scale || o.distance_scale)
             ? Criteria(Criteria::Edge_criteria(DBL_MAX),
                        Criteria::Facet_criteria(o.facet_angle_deg, ScaledField{o.facet_size, size_scale},
                                                 ScaledField{o.facet_distance, distance_scale}),
                        Criteria::Cell_criteria(o.cell_radius_edge_ratio, ScaledField{o.cell_size, size_scale}))
             : Criteria(p::facet_angle = o.facet_angle_deg, p::facet_size = o.facet_size,
                        p::facet_distance = o.facet_distance, p::cell_radius_edge_ratio = o.cell_radius_edge_ratio,
                        p::cell_size = o.cell_size);
}

/// Inserts Mesh_3's own initial points (random rays from the box centre, as
/// make_mesh_3 does) plus the bisected seed pairs as surface vertices: the
/// seeds reach every boundary component (the rays can miss an inner one).
void seed_surface(C3t3& c3t3, const Domain& domain, const Points& seed_inside, const Points& seed_outside) {
  std::vector<std::pair<K::Point_3, Domain::Index>> initial;
  domain.construct_initial_points_object()(std::back_inserter(initial));
  auto intersect = domain.construct_intersection_object();
  for (int i = 0; i < seed_inside.rows(); ++i) {
    const K::Point_3 a(seed_inside(i, 0), seed_inside(i, 1), seed_inside(i, 2));
    const K::Point_3 b(seed_outside(i, 0), seed_outside(i, 1), seed_outside(i, 2));
    const auto hit = intersect(K::Segment_3(a, b));
    if (std::get<2>(hit) != 0) initial.emplace_back(std::get<0>(hit), std::get<1>(hit));
  }
  Tr& tr = c3t3.triangulation();
  auto cwp = tr.geom_traits().construct_weighted_point_3_object();
  for (const auto& [pt, idx] : initial) {
    const auto v = tr.insert(cwp(pt));
    if (v == Tr::Vertex_handle()) continue;  // hidden point
    c3t3.set_dimension(v, 2);
    c3t3.set_index(v, idx);
  }
}

/// ODT smoothing, sliver perturbation and exudation, as the options ask; times in `rep`.
void optimize_mesh(C3t3& c3t3, const Domain& domain, const TetrahedralizeOptions& o, TetrahedralizeReport& rep) {
  namespace p = CGAL::parameters;
  Timer timer;
  if (o.odt_iterations > 0) {
    // ODT smoothing (bounded iteration count, no time limit: deterministic)
    // evens out the vertex distribution, which leaves far fewer slivers for
    // the expensive perturbation step.
    CGAL::odt_optimize_mesh_3(c3t3, domain, p::time_limit = 0, p::max_iteration_number = o.odt_iterations,
                              p::convergence = 0.02, p::freeze_bound = 0.01);
  }
  rep.odt_s = timer.seconds();
  timer.reset();
  if (o.perturb_sliver_bound_deg > 0) {
    // CGAL's perturb_mesh_3 with its default strategies minus most of the
    // last one: the random (Li) perturbation, 100 trials per vertex, is what
    // makes perturbation take minutes on a thin shell where slivers span the
    // layer, each trial costing domain projections. Gradient moves first, a
    // few random trials last.
    using Criterion = CGAL::Mesh_3::Min_dihedral_angle_criterion<Tr>;
    using Perturber = CGAL::Mesh_3::Sliver_perturber<C3t3, Domain, Criterion>;
    Criterion criterion(o.perturb_sliver_bound_deg, c3t3.triangulation());
    Perturber perturber(c3t3, domain, criterion);
    perturber.add_perturbation(new CGAL::Mesh_3::Sq_radius_perturbation<C3t3, Domain, Criterion>(40, 0.05));
    perturber.add_perturbation(new CGAL::Mesh_3::Volume_perturbation<C3t3, Domain, Criterion>(40, 0.05));
    perturber.add_perturbation(new CGAL::Mesh_3::Dihedral_angle_perturbation<C3t3, Domain, Criterion>(40, 0.05));
    if (o.perturb_random_trials > 0)
      perturber.add_perturbation(
          new CGAL::Mesh_3::Li_random_perturbation<C3t3, Domain, Criterion>(o.perturb_random_trials, 0.15));
    perturber.set_time_limit(o.perturb_time_limit_s);
    rep.perturb_time_limit_reached = (perturber() == CGAL::TIME_LIMIT_REACHED);
  }
  rep.perturb_s = timer.seconds();
  timer.reset();
  if (o.exude_sliver_bound_deg > 0)
    CGAL::exude_mesh_3(c3t3, p::time_limit = o.exude_time_limit_s, p::sliver_bound = o.exude_sliver_bound_deg);
  rep.exude_s = timer.seconds();
}

/// The mesh of the complex: nodes in the order CGAL stores them, cells in the complex.
TetMesh extract_mesh(const C3t3& c3t3) {
  TetMesh mesh;
  const Tr& tr = c3t3.triangulation();
  std::unordered_map<Tr::Vertex_handle, int> index;
  std::vector<Vec3> pts;
  for (auto v = tr.finite_vertices_begin(); v != tr.finite_vertices_end(); ++v) {
    index[v] = int(pts.size());
    const auto& pt = tr.point(v);
    pts.emplace_back(pt.x(), pt.y(), pt.z());
  }
  mesh.nodes.resize(pts.size(), 3);
  for (size_t i = 0; i < pts.size(); ++i) mesh.nodes.row(i) = pts[i].transpose();
  std::vector<std::array<int, 4>> cells;
  for (auto c = c3t3.cells_in_complex_begin(); c != c3t3.cells_in_complex_end(); ++c)
    cells.push_back({index.at(c->vertex(0)), index.at(c->vertex(1)), index.at(c->vertex(2)),
                     index.at(c->vertex(3))});
  require(!cells.empty(), "tetrahedralize_implicit: Mesh_3 produced no tets (region empty or missed; ",
          "check the inside function, the box and the seeds)");
  mesh.elements.resize(cells.size(), 4);
  for (size_t t = 0; t < cells.size(); ++t)
    for (int i = 0; i < 4; ++i) mesh.elements(t, i) = cells[t][i];

  return mesh;
}

}  // namespace

TetMesh tetrahedralize_implicit(const std::function<bool(const Vec3&)>& inside, const Vec3& box_min,
                                const Vec3& box_max, const Points& seed_inside, const Points& seed_outside,
                                const TetrahedralizeOptions& o, TetrahedralizeReport* report) {
  require(seed_inside.rows() == seed_outside.rows(), "tetrahedralize_implicit: ", seed_inside.rows(),
          " inside seeds but ", seed_outside.rows(), " outside seeds (expected equal counts)");
  require((box_max - box_min).minCoeff() > 0, "tetrahedralize_implicit: empty bounding box");
  require(o.facet_size > 0 && o.cell_size > 0 && o.facet_distance > 0,
          "tetrahedralize_implicit: facet_size, cell_size and facet_distance must be > 0");
  require(o.max_vertices > 0, "tetrahedralize_implicit: max_vertices = ", o.max_vertices, ", expected > 0");
  TetrahedralizeReport local;
  TetrahedralizeReport& rep = report ? *report : local;
  rep = TetrahedralizeReport{};

  // Mesh_3 draws random numbers (initial rays, perturbation) from the default
  // generator and from the domain's: fix both so the mesh is reproducible.
  CGAL::get_default_random() = CGAL::Random(o.seed);
  CGAL::Random domain_rng(o.seed);

  // Outside the box is outside the region, whatever `inside` says: Mesh_3
  // bisects dual Voronoi segments that reach metres away, and a region that
  // leaks out of the box (a wrong inside test far away) is an unbounded
  // surface that refinement never finishes (scripts/results/cgal_hang.md).
  LabelFunction label = [&inside, box_min, box_max](const K::Point_3& p) {
    const Vec3 x(p.x(), p.y(), p.z());
    if ((x.array() < box_min.array()).any() || (x.array() > box_max.array()).any()) return 0;
    return inside(x) ? 1 : 0;
  };
  const K::Iso_cuboid_3 box(box_min.x(), box_min.y(), box_min.z(), box_max.x(), box_max.y(), box_max.z());
  namespace p = CGAL::parameters;
  Domain domain(p::function = label, p::bounding_object = box,
                p::relative_error_bound = o.relative_error_bound, p::p_rng = &domain_rng);

  // Uniform criteria unless a sizing field is given (mesh_criteria).
  const std::function<double(const Vec3&)> one = [](const Vec3&) { return 1.0; };
  const Criteria criteria = mesh_criteria(o, one);

  C3t3 c3t3;
  seed_surface(c3t3, domain, seed_inside, seed_outside);
  Timer timer;
  // A vertex budget turns runaway refinement (criteria the surface cannot
  // meet, or a broken inside test) into one clear error instead of a hang.
  CGAL::parameters::internal::Mesh_3_options budget;
  CGAL::Mesh_error_code refine_code = CGAL::CGAL_MESH_3_NO_ERROR;
  budget.maximal_number_of_vertices = std::size_t(o.max_vertices);
  budget.pointer_to_error_code = &refine_code;
  CGAL::refine_mesh_3(c3t3, domain, criteria, p::no_perturb(), p::no_exude(), p::no_reset_c3t3(), budget);
  rep.refine_s = timer.seconds();
  require(refine_code == CGAL::CGAL_MESH_3_NO_ERROR, "tetrahedralize_implicit: Delaunay refinement stopped at ",
          c3t3.triangulation().number_of_vertices(), " vertices after ", rep.refine_s,
          " s, the limit TetrahedralizeOptions::max_vertices = ", o.max_vertices,
          " (facet_distance ", o.facet_distance, " m, facet_size ", o.facet_size, " m, cell_size ", o.cell_size,
          " m, facet_angle ", o.facet_angle_deg,
          " deg); loosen facet_distance or the sizes, or check that the region is bounded by the box");
  optimize_mesh(c3t3, domain, o, rep);

  TetMesh mesh = extract_mesh(c3t3);
  rep.flipped = orient_tets_positively(mesh);
  if (o.remove_boundary_slivers_below_deg > 0)
    rep.removed_boundary_slivers = remove_boundary_slivers(mesh, o.remove_boundary_slivers_below_deg);
  compact_nodes(mesh);
  rep.quality = tet_quality_report(mesh, o.remove_boundary_slivers_below_deg > 0 ? o.remove_boundary_slivers_below_deg : 8.0);
  return mesh;
}

Triangles tet_boundary_faces(const TetMesh& mesh) {
  const auto count = face_counts(mesh.elements);
  std::vector<std::array<int, 3>> faces;
  for (int t = 0; t < mesh.num_elements(); ++t)
    for (const auto& f : kFace) {
      const auto& e = mesh.elements;
      if (count.at(sorted_face(e(t, f[0]), e(t, f[1]), e(t, f[2]))) == 1)
        faces.push_back({e(t, f[0]), e(t, f[1]), e(t, f[2])});
    }
  Triangles F(faces.size(), 3);
  for (size_t i = 0; i < faces.size(); ++i) F.row(i) << faces[i][0], faces[i][1], faces[i][2];
  return F;
}

}  // namespace sflsh
