#include "sflsh/sim/step_report.hpp"

#include <sstream>

namespace sflsh {

const char* to_string(StepOutcome outcome) {
  switch (outcome) {
    case StepOutcome::Accepted: return "accepted";
    case StepOutcome::Damped: return "damped";
    case StepOutcome::Rejected: return "rejected";
  }
  return "unknown";
}

std::string StepReport::summary() const {
  std::ostringstream os;
  os << "t = " << time << " s: " << iterations << " Newton iteration(s), " << to_string(outcome) << " ("
     << accepted << " accepted, " << damped << " damped, " << rejected << " rejected";
  if (iterations_after_damping > 0) os << "; " << iterations_after_damping << " added after a damped one";
  if (iterations_for_nonlinearity > 0) os << "; " << iterations_for_nonlinearity << " added for nonlinearity";
  os << ")\n";
  os << "  energy " << energy_before << " -> " << energy_after << " J, |grad| " << grad_norm_before << " -> "
     << grad_norm_after << ", Newton decrement " << newton_decrement << ", step scale " << step_scale << "\n";
  os << "  terms:";
  for (const auto& e : energies) os << " " << e.name << "=" << e.value;
  os << "\n  time " << ms_total << " ms (assemble " << ms_assemble << ", solve " << ms_solve << "; per term:";
  for (const auto& e : energies) os << " " << e.name << " " << e.ms;
  os << ")\n";
  return os.str();
}

}  // namespace sflsh
