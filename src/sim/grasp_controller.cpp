#include "sflsh/sim/grasp_controller.hpp"

#include <algorithm>
#include <cmath>

#include "sflsh/core/error.hpp"

namespace sflsh {

GraspController::GraspController(GraspOptions options) : options_(std::move(options)) {
  require(!options_.sensors.empty(), "grasp: the jaw has no proximity sensors");
  require(std::isfinite(options_.closure_threshold), "grasp: closure threshold must be finite");
  for (const ProximitySensor& s : options_.sensors)
    require(s.origin.allFinite() && s.direction.allFinite() && s.direction.norm() > 0 && s.range >= 0,
            "grasp: a proximity sensor needs a finite origin, a non-zero direction and a range >= 0 m");
}

void GraspController::restore(std::vector<Anchor> anchors) {
  for (const Anchor& a : anchors)
    require(a.point >= 0 && a.offset.allFinite(), "grasp: restored anchor of point ", a.point,
            " needs a point >= 0 and a finite offset");
  anchors_ = std::move(anchors);
}

bool GraspController::update(double time, const Isometry& jaw_pose, double closure, const Points& skin,
                             const Triangles& faces) {
  require(std::isfinite(closure), "grasp: closure is not finite at t = ", time, " s");
  const bool closed = closure < options_.closure_threshold;
  if (!closed) {
    if (anchors_.empty()) return false;
    GraspEvent e{GraspEvent::Kind::Release, time, {}, {}};
    for (const Anchor& a : anchors_) e.points.push_back(a.point);
    log_.push_back(std::move(e));
    anchors_.clear();
    return true;
  }
  if (!anchors_.empty()) return false;  // holding: keep the offsets of the grasp
  const TriangleRaycaster caster(skin, faces);
  GraspEvent e{GraspEvent::Kind::Grasp, time, {}, {}};
  for (const ProximitySensor& s : options_.sensors) {
    const RayHit hit = sense(s, jaw_pose, caster);
    if (!hit.hit || std::count(e.faces.begin(), e.faces.end(), hit.face)) continue;
    e.faces.push_back(hit.face);
    for (int c = 0; c < 3; ++c) {
      const int v = faces(hit.face, c);
      if (std::count(e.points.begin(), e.points.end(), v)) continue;
      e.points.push_back(v);
      anchors_.push_back({v, jaw_pose.inverse() * Vec3(skin.row(v).transpose())});
    }
  }
  if (anchors_.empty()) return false;
  log_.push_back(std::move(e));
  return true;
}

}  // namespace sflsh
