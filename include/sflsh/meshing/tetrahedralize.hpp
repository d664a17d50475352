#pragma once
// Tetrahedralization of an implicitly given region with CGAL Mesh_3
// (Delaunay refinement, then sliver perturbation and exudation). CGAL stays
// inside the .cpp; the interface is Eigen only.
#include <functional>
#include <string>

#include "sflsh/core/types.hpp"
#include "sflsh/mesh/tet_mesh.hpp"
#include "sflsh/mesh/tet_quality.hpp"

namespace sflsh {

/// Mesh_3 criteria and optimisation settings. Lengths in metres.
struct TetrahedralizeOptions {
  double facet_angle_deg = 25.0;       ///< lower bound on boundary-triangle angles
  double facet_size = 0.035;           ///< upper bound on boundary-triangle circumradius (m)
  double facet_distance = 0.0007;      ///< upper bound on boundary-triangle-to-surface distance (m)
  double cell_radius_edge_ratio = 3.0; ///< upper bound on circumradius / shortest edge
  double cell_size = 0.05;             ///< upper bound on tet circumradius (m)
  /// Optional sizing field: a factor (> 0) on facet_size and cell_size at a
  /// point (m), so the mesh can be coarser where detail does not matter.
  /// Empty = uniform sizes. Must be deterministic and should vary slowly
  /// (Delaunay refinement grades the mesh between sizes by itself).
  std::function<double(const Vec3&)> size_scale;
  /// Optional factor (> 0) on facet_distance at a point; empty = uniform.
  std::function<double(const Vec3&)> distance_scale;
  /// Bisection precision of boundary points, relative to the box diagonal.
  double relative_error_bound = 1e-6;
  /// Iterations of ODT smoothing after refinement (0 = none).
  int odt_iterations = 0;
  /// Sliver perturbation target (deg); 0 skips perturbation. Perturbation
  /// with no time limit can run long when the bound is ambitious (its last
  /// strategy is random), so keep it modest and let exudation and the
  /// post-pass handle the rest.
  double perturb_sliver_bound_deg = 8.0;
  /// Random-move trials per vertex in the last perturbation strategy
  /// (CGAL's default is 100, which can take minutes; 0 = gradient moves only).
  int perturb_random_trials = 10;
  /// Sliver exudation target (deg); 0 skips exudation.
  double exude_sliver_bound_deg = 12.0;
  /// Time limits (s) of the two optimisers; 0 = none. The result is
  /// deterministic unless a limit is reached (then it depends on machine
  /// speed; TetrahedralizeReport says so). Perturbation in thin shells can
  /// otherwise run for minutes, so it gets a generous safety limit.
  double perturb_time_limit_s = 120.0;
  double exude_time_limit_s = 0.0;
  /// After optimisation, boundary tets (two or more faces on the boundary,
  /// all nodes on it) whose smallest dihedral angle is below this are
  /// removed: they are flat caps that add nothing to the volume.
  double remove_boundary_slivers_below_deg = 8.0;
  /// Vertex budget of Delaunay refinement: reaching it throws sflsh::Error
  /// naming the criteria instead of refining on (a surface the criteria
  /// cannot resolve would otherwise refine for hours). The procedural
  /// body's default shell mesh has ~12k nodes.
  long max_vertices = 1000000;
  unsigned seed = 1234;                ///< CGAL random seed (deterministic output)
};

/// What tetrahedralize_implicit did.
struct TetrahedralizeReport {
  double refine_s = 0, odt_s = 0, perturb_s = 0, exude_s = 0;
  int removed_boundary_slivers = 0;
  bool perturb_time_limit_reached = false;  ///< if true the mesh depends on timing
  int flipped = 0;  ///< tets reoriented to positive orientation
  TetQualityReport quality;
};

/// Tets of the region {x : inside(x)} inside the box [box_min, box_max]
/// (which must contain the region with some margin; points outside the box
/// count as outside whatever `inside` says). `inside` is queried at
/// arbitrary points (millions of times) and must be deterministic.
/// `seed_inside`/`seed_outside` (#S by 3 each) are pairs of points on either
/// side of the boundary, at least one pair per connected boundary component
/// (e.g. the inner bone surface): the boundary point found by bisection on
/// each pair seeds Delaunay refinement, so no component is missed; more
/// initial points come from Mesh_3's random rays (fixed seed).
/// Returns nodes (#N by 3, only those used by tets) and positively oriented
/// tets; throws sflsh::Error if the result is empty.
TetMesh tetrahedralize_implicit(const std::function<bool(const Vec3&)>& inside, const Vec3& box_min,
                                const Vec3& box_max, const Points& seed_inside, const Points& seed_outside,
                                const TetrahedralizeOptions& options, TetrahedralizeReport* report = nullptr);

/// Boundary faces of a tet mesh (faces belonging to exactly one tet), #B by 3,
/// oriented counter-clockwise seen from outside the mesh.
Triangles tet_boundary_faces(const TetMesh& mesh);

}  // namespace sflsh
