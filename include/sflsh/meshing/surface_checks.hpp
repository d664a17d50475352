#pragma once
// Topological and geometric checks of a triangle surface: closedness,
// manifoldness, orientation, components, genus, volume and self-intersection.
// Used by `sflsh body info` and by the tests of every module that makes surfaces.
#include <string>

#include "sflsh/core/types.hpp"

namespace sflsh {

/// What check_surface found. Counts refer to the input arrays as given.
struct SurfaceReport {
  int num_vertices = 0;           ///< rows of V
  int num_faces = 0;              ///< rows of F
  int num_edges = 0;              ///< distinct undirected edges
  int num_boundary_edges = 0;     ///< edges used by exactly one face
  int num_nonmanifold_edges = 0;  ///< edges used by three or more faces
  int num_nonmanifold_vertices = 0;  ///< vertices whose face fan is not one disc/half-disc
  int num_unreferenced_vertices = 0; ///< vertices used by no face
  int num_degenerate_faces = 0;   ///< faces with a repeated vertex index
  int num_misoriented_edges = 0;  ///< interior edges traversed in the same direction by both faces
  /// Every edge is shared by exactly two faces.
  bool is_closed = false;
  /// Edge- and vertex-manifold, no degenerate faces.
  bool is_manifold = false;
  /// Every two-face edge is traversed in opposite directions by its faces.
  bool consistently_oriented = false;
  /// Connected components of the face graph (faces linked through shared edges).
  int num_components = 0;
  /// V - E + F over the referenced vertices.
  int euler_characteristic = 0;
  /// (2·components − χ)/2 for a closed manifold mesh; -1 when that does not apply.
  int genus = -1;
  /// Signed enclosed volume (m³ for metres): Σ det(v0,v1,v2)/6; positive when
  /// the faces are counter-clockwise seen from outside.
  double signed_volume = 0.0;
  /// Total triangle area (m²).
  double area = 0.0;
  /// Whether the self-intersection test ran (it needs an oriented 2-manifold,
  /// and test_self_intersection=true).
  bool self_intersection_tested = false;
  /// CGAL::Polygon_mesh_processing::does_self_intersect on the mesh.
  bool self_intersects = false;
  double min_edge_length = 0.0;   ///< metres
  double mean_edge_length = 0.0;  ///< metres
  double max_edge_length = 0.0;   ///< metres
  Vec3 bbox_min = Vec3::Zero();   ///< per-axis minimum over referenced vertices
  Vec3 bbox_max = Vec3::Zero();   ///< per-axis maximum over referenced vertices
  /// Extent along Y (the up axis), metres.
  double height() const { return bbox_max.y() - bbox_min.y(); }
  /// Closed, manifold, consistently oriented, one component, genus 0, positive
  /// volume and (when tested) free of self-intersections.
  bool is_valid_body_surface() const;
  /// One line, e.g. "9012 vertices, 18020 faces, closed, manifold, oriented,
  /// 1 component, genus 0, volume 0.0712 m^3, no self-intersections, height 1.750 m".
  std::string describe() const;
};

/// Checks the surface (#V by 3 vertices, #F by 3 faces). With
/// `test_self_intersection`, runs CGAL's does_self_intersect when the mesh is
/// an oriented 2-manifold (otherwise self_intersection_tested stays false).
/// Throws sflsh::Error if a face index is out of range or a value is not finite.
SurfaceReport check_surface(const Points& V, const Triangles& F, bool test_self_intersection = true);

/// Generalized winding number of the closed surface (V, F) around point p
/// (Jacobson et al. 2013, eq. 5 via van Oosterom–Strackee solid angles):
/// ≈1 inside an outward-oriented closed surface, ≈0 outside.
double winding_number(const Points& V, const Triangles& F, const Vec3& p);

}  // namespace sflsh
