#pragma once
// Internals of the built-in procedural body (include/sflsh/body/procedural_body.hpp):
//   procedural_anatomy.cpp  — body parameters → skeleton (anthropometric joint
//                             placement) and the implicit primitives (girth profiles),
//   procedural_surface.cpp  — the implicit body (smooth union) and its
//                             polygonization (marching tetrahedra + smoothing),
//   procedural_body.cpp     — assembly: LBS weights, joint regressor, shape space.
#include <array>
#include <string>
#include <vector>

#include "sflsh/core/types.hpp"

namespace sflsh::procedural {

/// Parameters of the parametric body. All zero = the template (a 1.75 m adult).
/// Each field is measured in units of the shape coefficient β it drives (see
/// shape_parameter_meanings), so "+1" is one unit of that β.
struct BodyParams {
  double stature = 0;         ///< β0: overall size (uniform scale, +3.2 % per unit)
  double girth = 0;           ///< β1: weight / girth of torso and limbs
  double muscle = 0;          ///< β2: arm, thigh, calf, shoulder and chest muscle
  double chest = 0;           ///< β3: chest width and depth
  double waist = 0;           ///< β4: waist width and depth
  double hips = 0;            ///< β5: hip width and buttocks
  double arm_length = 0;      ///< β6: upper arm + forearm length
  double leg_length = 0;      ///< β7: thigh + shank length
  double shoulder_width = 0;  ///< β8: shoulder width (collar and shoulder joints)
  double belly = 0;           ///< β9: belly protrusion
  /// Adds `amount` units to parameter `index` (0..kNumShapeParameters-1).
  void add(int index, double amount);
};

inline constexpr int kNumShapeParameters = 10;

/// Meaning of each shape parameter, one line each (BodyModel::shape_meanings).
const std::array<std::string, kNumShapeParameters>& shape_parameter_meanings();

/// Stature at all-zero parameters (metres).
inline constexpr double kBaseStature = 1.75;
/// Relative size change per unit of β0.
inline constexpr double kStaturePerUnit = 0.032;

/// Landmarks: the 24 SMPL joints followed by end points of the terminal segments.
enum Landmark : int {
  kHeadTop = 24,
  kLeftFingertip,
  kRightFingertip,
  kLeftToeTip,
  kRightToeTip,
  kNumLandmarks
};
using Landmarks = std::array<Vec3, kNumLandmarks>;

/// Joint and landmark positions (metres, Y up, body facing +Z, left = +X,
/// feet on y = 0) from anthropometric segment proportions.
Landmarks make_landmarks(const BodyParams& params);

/// One piece of the implicit body: a tapered capsule with an elliptic cross
/// section from `a` to `b`; `e1` is the direction of the first cross-section
/// axis (made orthogonal to b - a). Radii r1/r2 along e1/e2 at each end, and
/// the axial radii of the two end caps.
struct Primitive {
  Vec3 a, b, e1;
  double r1a, r2a, r1b, r2b;
  double cap_a, cap_b;
};

/// The implicit primitives of the body for `params` (smooth union = surface),
/// placed on the skeleton of make_landmarks(params).
std::vector<Primitive> make_primitives(const BodyParams& params);

/// A bone segment carrying LBS weight for joint `joint`, between landmarks.
struct WeightSegment {
  int joint, from, to;
};
/// The segments used for skinning weights and for carrying vertices along
/// with the skeleton when a shape parameter moves joints.
const std::vector<WeightSegment>& weight_segments();

/// Smooth union (log-sum-exp soft minimum) of the primitives' fields: < 0
/// inside, > 0 outside, ≈ distance near the surface.
class BodyImplicit {
 public:
  BodyImplicit(std::vector<Primitive> primitives, double blend_radius);
  double value(const Vec3& p) const;
  /// Value and gradient (forward differences, step 1e-6 m).
  double value_and_gradient(const Vec3& p, Vec3* gradient) const;
  Vec3 gradient(const Vec3& p) const;
  /// Newton steps along the gradient onto the zero level set (to 1e-7 m);
  /// `normal`, if given, receives the unit outward normal there.
  Vec3 project(const Vec3& p, Vec3* normal = nullptr) const;
  /// Axis-aligned bounds of all primitives.
  void bounds(Vec3* lo, Vec3* hi) const;

 private:
  struct Prepared {
    Vec3 a, u, e1, e2;
    double length;
    Vec3 box_lo, box_hi;  // bounds expanded by kCullMargin
    Primitive p;
  };
  std::vector<Prepared> prims_;
  double blend_;
};

/// Triangle surface of the zero level set by marching tetrahedra on a grid of
/// spacing `cell` (metres): closed, 2-manifold, outward-oriented, but with
/// many slivers (see improve_surface).
void polygonize(const BodyImplicit& body, double cell, Points* V, Triangles* F);

/// Cleans a polygonized surface in place: collapses the shortest edges (link
/// condition, no face flips, no edge longer than `max_edge`) until at most
/// `target_vertices` remain, then relaxes vertices tangentially with
/// reprojection onto the zero set (`smoothing_passes` passes).
void improve_surface(const BodyImplicit& body, int target_vertices, double max_edge, int smoothing_passes,
                     Points* V, Triangles* F);

/// Vertex adjacency (sorted neighbour lists) of a triangle mesh.
std::vector<std::vector<int>> vertex_neighbours(int num_vertices, const Triangles& F);

}  // namespace sflsh::procedural
