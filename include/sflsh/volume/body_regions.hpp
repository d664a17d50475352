#pragma once
// Body regions of the tet mesh (material zones, thickness-map keys) and their
// default materials. A region is decided by the dominant skinning joint of a
// tet and, on the torso/hips, by which way the flesh faces (front = +Z, the
// SMPL facing direction).
#include <string>
#include <vector>

#include "sflsh/asset/avatar.hpp"
#include "sflsh/core/types.hpp"

namespace sflsh {

/// Region names, in index order: torso, belly, chest, buttocks, thigh, calf,
/// upper_arm, forearm, neck, head, hand, foot.
const std::vector<std::string>& body_region_names();

/// Index of a region by name; throws naming the unknown name and listing the known ones.
int body_region_index(const std::string& name);

/// Region of a point whose dominant SMPL joint is `joint`, with `facing` =
/// cosine between (point - skeleton point) and the body's forward axis (+Z),
/// and `height_above_hip` = point height minus its side's hip joint height
/// (m, only used to tell buttocks from thighs).
int body_region_of(int joint, double facing, double height_above_hip);

/// Default material per region (index order of body_region_names()): soft
/// tissue E ≈ 5e3..4e4 Pa (fat-rich regions softest), ν = 0.45, ρ = 1000
/// kg/m^3; stiffer along the bone than through the thickness. Head, hands
/// and feet are skinned (not simulated); their entries are stiff placeholders.
std::vector<RegionMaterial> default_region_materials();

/// SMPL joints whose flesh follows skinning only (head, wrists+hands,
/// ankles+feet; seed §2). Neck and collars stay simulated.
bool is_skinned_joint(int joint);

}  // namespace sflsh
