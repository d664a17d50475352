#pragma once
// A Model and one State, stepped together: the convenient way to run a scene
// (sim/step.hpp is the function underneath). The simulator builds no terms:
// whoever builds the scene adds them to the Model (avatar_model.hpp for one
// avatar; scene/ for scene files).
//
// The single-body members (reset(bones), step(target_bones), state(), ...)
// act on body 0, for the one-avatar case.
#include <memory>
#include <vector>

#include "sflsh/sim/avatar_model.hpp"
#include "sflsh/sim/model.hpp"
#include "sflsh/sim/posed_points.hpp"
#include "sflsh/sim/state.hpp"
#include "sflsh/sim/step.hpp"
#include "sflsh/sim/step_report.hpp"

namespace sflsh {

class Simulator {
 public:
  /// At rest: every bone G_i = I, z = 0, time 0.
  explicit Simulator(std::shared_ptr<const Model> model);

  const Model& model() const { return *model_; }
  std::shared_ptr<const Model> model_ptr() const { return model_; }
  /// The time step h (s).
  double h() const { return model_->options().h; }

  /// Advances every body by h (step.hpp).
  StepReport step(const StepInputs& inputs);
  /// One body: target bones at t + h (24 world transforms; the prescribed
  /// bones when kinematic, tracking targets otherwise) and the target pose.
  StepReport step(const std::vector<Isometry>& target_bones, const BodyPose& target_pose = {});

  /// Resets body 0 to `bones` with z = 0 and zero velocity, time 0 (one body).
  void reset(const std::vector<Isometry>& bones);
  /// Resets body 0: q_t = q, q_{t−1} = q_previous, and the time (one body).
  void reset(const Configuration& q, const Configuration& q_previous, double time = 0.0);
  /// The whole state (every body, the time); set_state validates it.
  const State& scene_state() const { return state_; }
  void set_state(const State& state);

  const Configuration& state(int body = 0) const { return state_.bodies.at(body).q; }
  const Configuration& previous_state(int body = 0) const { return state_.bodies.at(body).q_prev; }
  double time() const { return state_.time; }
  /// A body's avatar (throws for a rigid object).
  const Avatar& avatar(int body = 0) const;
  /// Global layout of a body's DoFs.
  const DofLayout& layout(int body = 0) const { return model_->bodies().at(body).layout; }

  /// #V by 3 posed skin surface of a body (m, world), pose blend shapes included.
  Points posed_surface(int body = 0) const;
  /// #V by 3 soft displacement u of a body's surface vertices (m, unposed space).
  Points soft_displacement(int body = 0) const;
  /// 24 by 3 world joint positions of a body (m).
  Points joints(int body = 0) const;

 private:
  std::shared_ptr<const Model> model_;
  State state_;
  std::vector<PosedPoints> surfaces_;  // per body
};

/// 24 identity bone transforms (the unposed configuration).
std::vector<Isometry> identity_bones();

}  // namespace sflsh
