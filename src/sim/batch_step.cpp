#include "sflsh/sim/batch_step.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "sflsh/core/error.hpp"
#include "sflsh/sim/step.hpp"

namespace sflsh {

void step_batch(const std::vector<const Model*>& models, std::vector<State>& states,
                const std::vector<StepInputs>& inputs, int threads, std::vector<StepReport>* reports) {
  const size_t n = states.size();
  require(models.size() == n && inputs.size() == n, "step_batch: ", models.size(), " models, ", n, " states and ",
          inputs.size(), " inputs; expected one of each per simulation");
  require(threads >= 0, "step_batch: threads = ", threads, ", expected >= 0 (0 = every core)");
  for (size_t i = 0; i < n; ++i) require(models[i] != nullptr, "step_batch: model ", i, " is null");
  if (reports) reports->assign(n, StepReport());
  auto one = [&](size_t i) {
    StepReport r = step(*models[i], states[i], inputs[i]);
    if (reports) (*reports)[i] = std::move(r);
  };
  if (threads == 1 || n <= 1) {
    for (size_t i = 0; i < n; ++i) one(i);
    return;
  }
  tbb::task_arena arena(threads == 0 ? tbb::task_arena::automatic : threads);
  // One simulation per task (grain 1): steps cost ~1 ms, far above TBB's overhead.
  arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t i = r.begin(); i != r.end(); ++i) one(i);
    });
  });
}

}  // namespace sflsh
