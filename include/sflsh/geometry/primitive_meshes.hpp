#pragma once
// Triangle surfaces of the analytic primitives (result files,
// exports and renders show the rigid objects), in the same local frames as
// primitive_sdfs.hpp: centred at the origin, axes of symmetry along +Y.
//
// Every vertex lies on the field's zero level (up to rounding), the faces are
// counter-clockwise seen from outside (outward normals), and the finite
// shapes are closed (each edge is used once in each direction), so the
// enclosed volume (divergence theorem) is positive and converges to the
// closed form as `resolution` grows. Round shapes are surfaces of revolution:
// `resolution` segments around Y, rings spaced about as far apart as the
// segments, one vertex at each pole.
//
// A plane has no finite surface: plane_patch_mesh gives a square piece of
// it, ONE open sheet oriented along the plane's normal (no thickness, no
// volume). Viewers draw it two-sided (the glTF export marks its material
// doubleSided; the software renderer shades both sides).
#include "sflsh/core/types.hpp"
#include "sflsh/geometry/primitive_sdfs.hpp"

namespace sflsh::geometry {

/// A triangle surface: #V by 3 vertices (m), #F by 3 faces (CCW from outside).
struct PrimitiveMesh {
  Points vertices;
  Triangles faces;
};

/// Sphere of `radius` (m, > 0): `resolution` (>= 3, default 32) segments
/// around Y and 2·max(2, resolution/4) steps from pole to pole (the capsule
/// with h = 0).
PrimitiveMesh sphere_mesh(double radius, int resolution = 32);

/// Box [-b, b] (b: half extents, m, each > 0); every face split into
/// `resolution` × `resolution` squares (cells; >= 1, default 1: 8 vertices,
/// 12 triangles).
PrimitiveMesh box_mesh(const Vec3& half_extents, int resolution = 1);

/// Capsule of `radius` r around the segment (0, ±h, 0) (h = half_length >= 0,
/// m): two hemispheres of max(2, resolution/4) rings each and a side split
/// along Y into rows about as long as a segment. `resolution` >= 3, default 32.
PrimitiveMesh capsule_mesh(double radius, double half_length, int resolution = 32);

/// Capped cylinder {ρ <= r, |y| <= h} (radius, half_height: m, > 0): flat caps
/// of concentric rings and a side split into rows, both spaced about as far
/// as the `resolution` (>= 3, default 32) segments around Y.
PrimitiveMesh cylinder_mesh(double radius, double half_height, int resolution = 32);

/// The shape's surface at `resolution` (see the functions above).
PrimitiveMesh primitive_mesh(const SphereSdf& shape, int resolution = 32);
PrimitiveMesh primitive_mesh(const BoxSdf& shape, int resolution = 1);
PrimitiveMesh primitive_mesh(const CapsuleSdf& shape, int resolution = 32);
PrimitiveMesh primitive_mesh(const CylinderSdf& shape, int resolution = 32);

/// A square patch of the plane {x : n·x = offset} (`normal` non-zero, made
/// unit here; `offset` m): centred at the projection of `center` (m) onto the
/// plane, side 2·half_size (m, > 0), split into resolution × resolution
/// squares (>= 1, default 1: 4 vertices, 2 triangles). One open sheet whose
/// faces point along n (out of PlaneSdf's solid). Its edges run along t1 and
/// t2 = n × t1, where t1 = n × e and e is the coordinate axis least aligned
/// with n (for the floor n = +Y: t1 = −Z, t2 = −X).
PrimitiveMesh plane_patch_mesh(const Vec3& normal, double offset, double half_size, const Vec3& center = Vec3::Zero(),
                               int resolution = 1);
PrimitiveMesh primitive_mesh(const PlaneSdf& shape, double half_size, const Vec3& center = Vec3::Zero(),
                             int resolution = 1);

/// A copy of the surface for display with smooth shading: vertices where faces
/// meet at more than `crease_degrees` (default 40°) between their normals are
/// split, one copy per group of faces within that angle of each other, so
/// area-weighted vertex normals stay sharp along box edges and cylinder rims
/// and smooth across a sphere. Vertex positions are unchanged; the result is
/// no longer closed as an index graph.
PrimitiveMesh split_sharp_edges(const Points& V, const Triangles& F, double crease_degrees = 40.0);

}  // namespace sflsh::geometry
