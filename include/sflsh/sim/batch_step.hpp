#pragma once
// Stepping a batch of independent simulations (e.g. a crowd of avatars) on
// several cores: one time step of every State, the States spread over the
// threads of a TBB arena. Each State owns its scratch (state.hpp) and the
// Model's terms are immutable (energy_term.hpp), so the States may share one
// Model; each State's step is exactly the serial step() (same operations in
// the same order), so the result does not depend on the thread count.
#include <vector>

#include "sflsh/sim/model.hpp"
#include "sflsh/sim/state.hpp"
#include "sflsh/sim/step_report.hpp"

namespace sflsh {

/// Advances every `states[i]` by one step of `*models[i]` with `inputs[i]`
/// (step.hpp), on at most `threads` threads (0 = every core TBB sees; 1 = in
/// the calling thread, in order). The three vectors must have the same size;
/// a Model may appear several times (it is only read). `reports`, if
/// non-null, is resized and gets each step's report. An exception from any
/// step is rethrown after the batch (then some States may have stepped and
/// others not).
void step_batch(const std::vector<const Model*>& models, std::vector<State>& states,
                const std::vector<StepInputs>& inputs, int threads, std::vector<StepReport>* reports = nullptr);

}  // namespace sflsh
