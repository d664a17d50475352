// The step starts admissible (contact_patch.hpp, "Life of a patch"): every
// patch tet keeps det F > 0 under the subspace's z at t and the δu carried
// over, before begin_step hands the patch to the step.
#include <unordered_map>
#include <vector>

#include "sflsh/sim/energies/contact_patch.hpp"
#include "sim/energies/contact_patch_cache.hpp"

namespace sflsh {

using contact_patch_detail::PatchCache;
using contact_patch_detail::PatchHistory;

namespace {
/// A released patch's tets keep at least this volume ratio det F as δu
/// decays (keep_start_admissible); below it the patch is minimized instead.
/// Far below what a release meets otherwise (a 20-fold crush): 0.5 changed a
/// pinch's release on the coarse box avatar of the scene goldens.
constexpr double kReleaseMinVolumeRatio = 0.05;
}  // namespace

std::vector<double> ContactPatchTerm::patch_tet_determinants(const TermCache& cache, const VecX& z,
                                                           const VecX& du) const {
  const PatchCache& c = static_cast<const PatchCache&>(cache);
  const std::vector<Vec3> u = contact_patch_detail::tet_node_subspace_displacements(*avatar_, c, z);
  std::vector<double> det(c.tets.size());
  for (size_t ti = 0; ti < c.tets.size(); ++ti) {
    Mat3 F = Mat3::Identity();
    for (int k = 0; k < 4; ++k) {
      const int slot = c.tet_slot[ti][size_t(k)];
      const Vec3 uk = slot >= 0 ? Vec3(u[size_t(c.tet_local[ti][size_t(k)])] + du.segment<3>(3 * slot))
                                : u[size_t(c.tet_local[ti][size_t(k)])];
      F += uk * grads_[c.tets[ti]].row(k);
    }
    det[ti] = F.determinant();
  }
  return det;
}

void ContactPatchTerm::keep_start_admissible(TermCache& cache, const VecX& z,
                                             const std::unordered_map<int, PatchHistory>& left, double decay) const {
  PatchCache& c = static_cast<PatchCache&>(cache);
  const Avatar& a = *avatar_;
  auto carried = [&](double scale) {  // the nodes' displacement at t, scaled, in slot order
    VecX du = VecX::Zero(3 * long(c.nodes.size()));
    for (size_t i = 0; i < c.nodes.size(); ++i) {
      const auto h = c.history.find(c.nodes[i]);
      if (h != c.history.end()) du.segment<3>(3 * long(i)) = scale * h->second.du;
    }
    return du;
  };
  // A node that left returns (with its history) to a tet that its last
  // micrometre kept admissible: a tet the subspace alone crushes.
  for (bool changed = !left.empty(); changed;) {
    changed = false;
    const std::vector<double> det = patch_tet_determinants(c, z, carried(1.0));
    for (size_t ti = 0; ti < c.tets.size(); ++ti) {
      if (det[ti] > 0) continue;
      for (int k = 0; k < 4; ++k) {
        const int n = a.tet.elements(c.tets[ti], k);
        const auto l = left.find(n);
        if (l == left.end() || c.history.count(n)) continue;
        c.history.emplace(n, l->second);
        if (!c.node_slot.count(n)) c.node_slot.emplace(n, int(c.nodes.size())), c.nodes.push_back(n);
        changed = true;
      }
    }
    if (changed) prepare_patch_tets(c);
  }
  auto remove_nodes = [&](const std::vector<char>& drop) {
    std::vector<int> kept;
    for (size_t i = 0; i < c.nodes.size(); ++i)
      if (!drop[i]) kept.push_back(c.nodes[i]);
    c.nodes = std::move(kept);
    prepare_patch_tets(c);
  };
  // New nodes in a tet the subspace inverts: left out while it does.
  for (;;) {
    const std::vector<double> det = patch_tet_determinants(c, z, carried(1.0));
    std::vector<char> drop(c.nodes.size(), 0);
    bool any = false;
    for (size_t ti = 0; ti < c.tets.size(); ++ti) {
      if (det[ti] > 0) continue;
      for (int k = 0; k < 4; ++k) {
        const int slot = c.tet_slot[ti][size_t(k)];
        if (slot >= 0 && !c.history.count(c.nodes[size_t(slot)])) drop[size_t(slot)] = 1, any = true;
      }
    }
    if (!any) break;
    remove_nodes(drop);
  }
  if (!c.releasing) return;
  // A released patch decays while the subspace can take its tets back: with
  // a tet crushed below kReleaseMinVolumeRatio of its volume (the subspace
  // alone nearly or wholly inverts it) δu stays minimized, its barrier holding the tet,
  // until the subspace relaxes. Prescribed there, δu froze the tet near
  // det F = 0 while z moved on, and the step's energy ran to 1e17.
  for (double d : patch_tet_determinants(c, z, carried(decay)))
    if (!(d >= kReleaseMinVolumeRatio)) {
      c.releasing = false;
      return;
    }
}

}  // namespace sflsh
