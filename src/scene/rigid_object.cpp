#include "sflsh/scene/rigid_object.hpp"

#include "sflsh/core/error.hpp"
#include "sflsh/core/rotation.hpp"
#include "sflsh/geometry/grid_sdf.hpp"
#include "sflsh/geometry/primitive_sdfs.hpp"
#include "sflsh/io/mesh_export.hpp"

namespace sflsh {
namespace {

/// Mass properties of a primitive by density, or scaled to the given mass.
template <class Shape>
geometry::MassProperties mass_of(const Shape& shape, const RigidObjectDescription& o) {
  if (o.density > 0) return geometry::mass_properties(shape, o.density);
  return geometry::mass_properties(shape, 1.0).with_mass(o.mass);
}

}  // namespace

RigidObjectModel make_rigid_object(const RigidObjectDescription& o) {
  RigidObjectModel m;
  const ShapeDescription& s = o.shape;
  const bool dynamic = o.kind == ObjectKind::Dynamic;
  switch (s.type) {
    case ShapeType::Plane: {
      require(!dynamic, s.location, ": a plane cannot be dynamic");
      m.field = std::make_shared<geometry::PlaneSdf>(s.normal, 0.0);
      m.surface = geometry::plane_patch_mesh(s.normal, 0.0, 0.5);
      break;
    }
    case ShapeType::Sphere: {
      auto f = std::make_shared<geometry::SphereSdf>(s.radius);
      m.surface = geometry::primitive_mesh(*f);
      if (dynamic) m.mass = mass_of(*f, o);
      m.field = f;
      break;
    }
    case ShapeType::Box: {
      auto f = std::make_shared<geometry::BoxSdf>(0.5 * s.size);
      m.surface = geometry::primitive_mesh(*f);
      if (dynamic) m.mass = mass_of(*f, o);
      m.field = f;
      break;
    }
    case ShapeType::Capsule: {
      auto f = std::make_shared<geometry::CapsuleSdf>(s.radius, 0.5 * s.length);
      m.surface = geometry::primitive_mesh(*f);
      if (dynamic) m.mass = mass_of(*f, o);
      m.field = f;
      break;
    }
    case ShapeType::Cylinder: {
      auto f = std::make_shared<geometry::CylinderSdf>(s.radius, 0.5 * s.length);
      m.surface = geometry::primitive_mesh(*f);
      if (dynamic) m.mass = mass_of(*f, o);
      m.field = f;
      break;
    }
    case ShapeType::Mesh: {
      try {
        const io::ImportedMesh mesh = io::read_mesh(s.mesh_file);
        m.surface.vertices = mesh.vertices * s.mesh_scale;
        m.surface.faces = mesh.faces;
        require(s.baked_sdf != nullptr, s.mesh_file, ": the mesh's SDF is not baked (the sflsh commands bake it; "
                "a program calls prepare_scene_assets, sflsh/scene_assets/scene_assets.hpp)");
        m.field = s.baked_sdf;
        m.bake_report = s.bake_report;
        if (dynamic)
          m.mass = o.density > 0
                       ? geometry::mesh_mass_properties(m.surface.vertices, m.surface.faces, o.density)
                       : geometry::mesh_mass_properties(m.surface.vertices, m.surface.faces, 1.0).with_mass(o.mass);
      } catch (const Error& e) {
        fail(s.location, ": ", e.what());
      }
      break;
    }
  }
  if (dynamic) m.shape_in_body.translation() = -m.mass.center;
  return m;
}

Isometry object_pose_at(const RigidObjectDescription& o, double t) {
  if (o.kind != ObjectKind::Kinematic || o.keyframes.empty()) return pose_at(o.position, o.orientation);
  const std::vector<Keyframe>& k = o.keyframes;
  if (t <= k.front().time) return pose_at(k.front().position, k.front().orientation);
  if (t >= k.back().time) return pose_at(k.back().position, k.back().orientation);
  size_t i = 1;
  while (k[i].time < t) ++i;
  const double a = (t - k[i - 1].time) / (k[i].time - k[i - 1].time);
  return pose_at((1 - a) * k[i - 1].position + a * k[i].position,
                   k[i - 1].orientation.normalized().slerp(a, k[i].orientation.normalized()));
}

Isometry pose_at(const Vec3& position, const Eigen::Quaterniond& orientation) {
  Isometry T = Isometry::Identity();
  T.linear() = orientation.normalized().toRotationMatrix();
  T.translation() = position;
  return T;
}

WorldFrame frame_between(const Isometry& before, const Isometry& after, double h) {
  WorldFrame f;
  f.pose = after;
  f.linear_velocity = (after.translation() - before.translation()) / h;
  f.angular_velocity = rotation_log(after.linear() * before.linear().transpose()) / h;
  return f;
}

}  // namespace sflsh
