#pragma once
// The grasp step of a two-jaw gripper (AMBF Alg. 3), pure logic:
// when the gripper's closure is below a threshold and one of the jaw's
// proximity sensors hits the skin within its range, the hit faces' vertices
// become anchors with their current offset in the jaw frame,
//   o_v = T_jaw⁻¹ x_v   (world x_v, jaw pose T_jaw at that step),
// so a new anchor starts at zero stretch (no jerk); they stay until the
// closure reaches the threshold again (release). Every sensor that hits
// contributes its face; a vertex shared by faces is anchored once. While the
// gripper is closed and holds nothing, sensing is repeated every step. Grasps
// and releases are logged.
//
// Anchors name skin vertices (rows of Avatar::surface_rest), i.e. rows of an
// AnchorTerm built on PosedPoints::at_surface; `skin` must be the positions of
// those points at the current state (PosedPoints::world, no pose blend shapes),
// the same points the anchor term moves.
#include <string>
#include <vector>

#include "sflsh/sim/energies/anchor.hpp"
#include "sflsh/sim/proximity_sensor.hpp"

namespace sflsh {

struct GraspOptions {
  std::vector<ProximitySensor> sensors;  ///< on the jaw, in its frame
  double closure_threshold = 0.2;        ///< grasp when closure < this (the scene's unit: rad or a fraction)
};

struct GraspEvent {
  enum class Kind { Grasp, Release };
  Kind kind = Kind::Grasp;
  double time = 0;           ///< s
  std::vector<int> faces;    ///< grasp: the hit faces
  std::vector<int> points;   ///< the vertices anchored (grasp) or released (release)
};

class GraspController {
 public:
  /// Throws without sensors or with a non-finite threshold.
  explicit GraspController(GraspOptions options);
  /// One step at `time` (s): jaw pose (world), closure, skin vertex positions
  /// (#V by 3, world) and their faces (#F by 3). Returns whether the anchors changed.
  bool update(double time, const Isometry& jaw_pose, double closure, const Points& skin, const Triangles& faces);
  /// The current anchors: skin vertex and offset in the jaw frame (m).
  const std::vector<Anchor>& anchors() const { return anchors_; }
  /// Holds `anchors` as if grasped before (a resumed checkpoint); the log is
  /// unchanged. Throws on a non-finite offset or a negative point.
  void restore(std::vector<Anchor> anchors);
  bool grasping() const { return !anchors_.empty(); }
  /// Whether update() at this closure would cast the sensors (closed, nothing
  /// held yet): only then does it read the skin (callers may pass an empty one otherwise).
  bool seeking(double closure) const { return closure < options_.closure_threshold && anchors_.empty(); }
  const std::vector<GraspEvent>& log() const { return log_; }
  const GraspOptions& options() const { return options_; }

 private:
  GraspOptions options_;
  std::vector<Anchor> anchors_;
  std::vector<GraspEvent> log_;
};

}  // namespace sflsh
