// The contact patch's history in a checkpoint (state_file.hpp): what a
// resumed run needs to go on as the uninterrupted one (the dent and its
// velocity), nothing begin_step recomputes.
#include <cmath>
#include <vector>

#include "sim/energies/contact_patch_cache.hpp"

namespace sflsh::contact_patch_detail {

std::vector<double> PatchCache::saved_state() const {
  std::vector<double> out;
  out.reserve(history.size() * kPatchHistoryValues);
  for (const auto& [n, h] : history) {
    out.push_back(double(n));
    for (const Vec3* v : {&h.du, &h.d_t, &h.du_next, &h.d_next, &h.du_back_next}) out.insert(out.end(), v->data(), v->data() + 3);
  }
  return out;
}

void PatchCache::restore_state(const std::vector<double>& values, const std::string& where) {
  require(values.size() % kPatchHistoryValues == 0, where, ": the contact patch's history has ", values.size(),
          " values, not a multiple of ", kPatchHistoryValues, " (a node, then δu, d_t, δu_next, d_next, du_back_next)");
  history.clear();
  int last = -1;
  for (size_t i = 0; i < values.size(); i += kPatchHistoryValues) {
    const double n = values[i];
    const size_t entry = i / kPatchHistoryValues;
    require(std::isfinite(n) && n == std::floor(n) && n > last && n < num_nodes, where, ": entry ", entry,
            " of the contact patch's history names node ", n, ": nodes must be whole, increasing and below ",
            num_nodes);
    for (size_t k = 1; k < kPatchHistoryValues; ++k)
      require(std::isfinite(values[i + k]), where, ": entry ", entry, " of the contact patch's history is not finite");
    PatchHistory h;
    const double* p = &values[i + 1];
    for (Vec3* v : {&h.du, &h.d_t, &h.du_next, &h.d_next, &h.du_back_next}) *v = Vec3(p[0], p[1], p[2]), p += 3;
    last = int(n);
    history.emplace(last, h);
  }
}

}  // namespace sflsh::contact_patch_detail
