#include "sflsh/sim/finite_guard.hpp"

#include <cmath>
#include <sstream>

#include "sflsh/body/smpl_skeleton.hpp"

namespace sflsh {
namespace {

std::string number(double v) {
  std::ostringstream o;
  o << v;
  return o.str();
}

// The first non-finite part of one configuration, or "".
std::string non_finite_part(const Configuration& q) {
  for (size_t b = 0; b < q.bones.size(); ++b)
    if (!q.bones[b].matrix().allFinite()) {
      std::string name = "bone " + std::to_string(b);
      if (b < size_t(kSmplJoints)) name += " (" + std::string(kSmplJointNames[b]) + ")";
      return name + " transform";
    }
  for (Eigen::Index i = 0; i < q.z.size(); ++i)
    if (!std::isfinite(q.z[i])) return "reduced DoF z[" + std::to_string(i) + "] = " + number(q.z[i]);
  return "";
}

}  // namespace

std::string NonFiniteReport::describe() const {
  if (finite()) return "all finite";
  std::string s;
  if (!term.empty()) s = "term '" + term + "'" + (body.empty() ? "" : " of body '" + body + "'") + "; ";
  return s + (body.empty() ? "" : "body '" + body + "': ") + what;
}

NonFiniteReport find_non_finite(const Model& model, const State& state, const StepReport& report) {
  NonFiniteReport r;
  const auto& terms = model.terms();
  bool all_nan = std::isnan(report.energy_after) && !report.energies.empty();
  for (const TermEnergy& e : report.energies) all_nan = all_nan && std::isnan(e.value);
  if (!all_nan) {
    for (size_t i = 0; i < report.energies.size(); ++i) {
      const TermEnergy& e = report.energies[i];
      if (std::isfinite(e.value)) continue;
      r.term = e.name;
      r.what = "energy " + number(e.value);
      // The report lists the model's terms in order; fall back to the name.
      const Model::BoundTerm* bound = nullptr;
      if (report.energies.size() == terms.size() && terms[i].term->name() == e.name) bound = &terms[i];
      for (size_t k = 0; !bound && k < terms.size(); ++k)
        if (terms[k].term->name() == e.name) bound = &terms[k];
      if (bound && !bound->bodies.empty()) r.body = model.bodies().at(bound->bodies.front()).name;
      break;
    }
  }
  // The state names the body for sure; keep the term found above.
  for (size_t b = 0; b < state.bodies.size(); ++b) {
    const std::string part = non_finite_part(state.bodies[b].q);
    if (part.empty()) continue;
    r.body = b < model.bodies().size() ? model.bodies()[b].name : "body " + std::to_string(b);
    r.what = part;
    return r;
  }
  if (r.what.empty() && !std::isfinite(report.energy_after) && !all_nan) r.what = "total energy " + number(report.energy_after);
  return r;
}

void require_finite_step(const Model& model, const State& state, const StepReport& report, long step,
                         const std::string& run) {
  NonFiniteReport r = find_non_finite(model, state, report);
  if (r.finite()) return;
  std::ostringstream o;
  o << run << ": non-finite value at step " << step << " (t = " << state.time << " s): " << r.describe()
    << "; stopped (try a smaller --dt, or check the motion and the material)";
  throw NonFiniteError(o.str(), step, std::move(r));
}

}  // namespace sflsh
