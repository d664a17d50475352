#pragma once
// Proximity sensors of a tool (AMBF Fig. 5): rays mounted in a
// tool's frame (origin, direction, range) cast against the posed skin — the
// triangles Avatar::surface_faces over the skin vertices at the current
// configuration, world. The first hit within range gives the face, its
// barycentric coordinates, the point and the distance along the ray.
//
// Broad phase: a bounding-volume hierarchy of axis-aligned boxes over the
// triangles (median split of the centroids along the longest axis, leaves of
// ≤ 4 triangles), rebuilt from the vertices each time the skin moves
// (O(F log F)); a ray visits only the boxes it crosses, nearest-first pruning
// by the closest hit so far.
#include <vector>

#include "sflsh/core/types.hpp"
#include "sflsh/geometry/aabb.hpp"
#include "sflsh/sim/configuration.hpp"

namespace sflsh {

/// The first intersection of a ray with a triangle mesh.
struct RayHit {
  bool hit = false;
  int face = -1;                ///< row of the face array
  Vec3 point = Vec3::Zero();    ///< world, m
  Vec3 bary = Vec3::Zero();     ///< weights of the face's three vertices (sum 1)
  double distance = 0;          ///< along the ray, m (the direction is unit)
};

/// Möller–Trumbore, both sides: the ray parameter t (m for a unit direction)
/// and barycentric (u, v) of the hit with triangle (a, b, c) — point
/// (1−u−v) a + u b + v c — or false when parallel or outside.
bool ray_triangle(const Vec3& origin, const Vec3& direction, const Vec3& a, const Vec3& b, const Vec3& c, double& t,
                  double& u, double& v);

class TriangleRaycaster {
 public:
  /// `vertices` #V by 3 (m), `faces` #F by 3 vertex indices (checked).
  TriangleRaycaster(const Points& vertices, const Triangles& faces);
  /// The nearest hit with 0 ≤ distance ≤ range (m) of the ray from `origin`
  /// along `direction` (normalized here; must be non-zero), or hit = false.
  RayHit cast(const Vec3& origin, const Vec3& direction, double range) const;
  /// Triangles whose exact test the last cast() ran (broad-phase efficiency).
  int last_tests() const { return tests_; }
  int num_faces() const { return int(faces_.rows()); }

 private:
  struct Node {
    geometry::Aabb box;
    int left = -1, right = -1;  // children, or −1 for a leaf
    int begin = 0, end = 0;     // leaf: order_[begin, end)
  };
  int build(int begin, int end, const std::vector<Vec3>& centroids);
  Points vertices_;
  Triangles faces_;
  std::vector<int> order_;
  std::vector<Node> nodes_;
  mutable int tests_ = 0;
};

/// A ray mounted on a tool: origin and direction in the tool's frame, range (m).
struct ProximitySensor {
  Vec3 origin = Vec3::Zero();
  Vec3 direction = Vec3(0, 0, 1);
  double range = 0.01;
};

/// Casts `sensor`, placed by `tool_pose` (world), against `skin`.
RayHit sense(const ProximitySensor& sensor, const Isometry& tool_pose, const TriangleRaycaster& skin);

}  // namespace sflsh
