#pragma once
// The point of a triangle closest to a query point (Ericson, "Real-Time
// Collision Detection", §5.1.5): the Voronoi region of the query among the
// triangle's vertices, edges and face decides, and the answer is given by its
// barycentric coordinates so that it can follow a moving triangle.
#include "sflsh/core/types.hpp"

namespace sflsh::geometry {

/// Barycentric coordinates (λ_a, λ_b, λ_c; ≥ 0, sum 1) of the point of
/// triangle (a, b, c) closest to p. A degenerate triangle gives one of its
/// closest vertices or edge points.
Vec3 closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);

}  // namespace sflsh::geometry
