#pragma once
// Inside/outside and closest-point queries against a closed triangle surface
// (CGAL AABB tree + Side_of_triangle_mesh, hidden behind a pimpl).
#include <memory>

#include "sflsh/core/types.hpp"

namespace sflsh {

class SurfaceQuery {
 public:
  /// `V` #V by 3, `F` #F by 3 (closed, consistently oriented for inside()).
  SurfaceQuery(const Points& V, const Triangles& F);
  ~SurfaceQuery();
  SurfaceQuery(SurfaceQuery&&) noexcept;
  SurfaceQuery& operator=(SurfaceQuery&&) noexcept;

  /// True if x is strictly inside the closed surface.
  bool inside(const Vec3& x) const;
  /// Distance from x to the surface (m).
  double distance(const Vec3& x) const;
  /// Signed distance (m, negative inside) from the closest point and the
  /// angle-weighted pseudo-normal of its feature (face, edge or vertex;
  /// Bærentzen & Aanæs 2005): exact sign for a closed, consistently oriented
  /// (counter-clockwise from outside) manifold surface, and much cheaper than
  /// ray casting.
  double signed_distance(const Vec3& x) const;
  /// Closest surface point to x; `face` receives its triangle and `bary`
  /// the barycentric coordinates in that triangle (sum 1, clamped >= 0).
  Vec3 closest_point(const Vec3& x, int* face = nullptr, Vec3* bary = nullptr) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace sflsh
