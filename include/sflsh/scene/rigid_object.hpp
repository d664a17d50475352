#pragma once
// A scene's rigid object made concrete: its signed distance field
// (exact for primitives, a baked grid for meshes), its surface for display,
// its mass properties (dynamic objects) and its pose over time (kinematic
// keyframes). Frames: the description's position/orientation place the
// shape's own frame (primitive_sdfs.hpp); a dynamic object's body frame sits
// at its centre of mass, shape_in_body = T(−centre).
#include <string>

#include "sflsh/geometry/mass_properties.hpp"
#include "sflsh/geometry/primitive_meshes.hpp"
#include "sflsh/geometry/sdf.hpp"
#include "sflsh/scene/scene_description.hpp"
#include "sflsh/sim/configuration.hpp"
#include "sflsh/sim/energy_term.hpp"

namespace sflsh {

struct RigidObjectModel {
  geometry::SdfPtr field;                 ///< in the shape frame
  geometry::PrimitiveMesh surface;        ///< shape frame, for results (a plane: a 1 m patch)
  geometry::MassProperties mass;          ///< dynamic objects only (density or mass)
  Isometry shape_in_body = Isometry::Identity();  ///< T(−centre of mass)
  std::string bake_report;                ///< mesh objects: what the SDF bake or cache did
};

/// Builds field, surface and (for dynamic objects) mass properties. A mesh
/// object's surface is read from its file and its field is the shape's
/// baked_sdf (prepare_scene_assets bakes it; without it: an error). Errors
/// name the object's location in the scene file.
RigidObjectModel make_rigid_object(const RigidObjectDescription& object);

/// The shape frame's pose at time t (s): the fixed pose of static and dynamic
/// objects (their initial one), or the keyframes of a kinematic object
/// (positions linear, orientations slerped, held before the first and after
/// the last keyframe).
Isometry object_pose_at(const RigidObjectDescription& object, double t);

/// The rigid transform at `position` (m) turned by `orientation` (normalized first).
Isometry pose_at(const Vec3& position, const Eigen::Quaterniond& orientation);

/// The world frame of a step that moves a frame from `before` to `after` over
/// h seconds: the pose `after`, the twist by finite difference (world).
WorldFrame frame_between(const Isometry& before, const Isometry& after, double h);

}  // namespace sflsh
