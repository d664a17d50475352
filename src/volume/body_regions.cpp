#include "sflsh/volume/body_regions.hpp"

#include "sflsh/core/error.hpp"

namespace sflsh {

const std::vector<std::string>& body_region_names() {
  static const std::vector<std::string> names = {"torso", "belly",   "chest", "buttocks", "thigh", "calf",
                                                 "upper_arm", "forearm", "neck", "head", "hand", "foot"};
  return names;
}

int body_region_index(const std::string& name) {
  const auto& names = body_region_names();
  for (size_t i = 0; i < names.size(); ++i)
    if (names[i] == name) return int(i);
  std::string known;
  for (const auto& n : names) known += (known.empty() ? "" : ", ") + n;
  fail("unknown body region '", name, "' (known: ", known, ")");
}

int body_region_of(int joint, double facing, double height_above_hip) {
  static const int torso = 0, belly = 1, chest = 2, buttocks = 3, thigh = 4, calf = 5, upper_arm = 6,
                   forearm = 7, neck = 8, head = 9, hand = 10, foot = 11;
  const bool front = facing > 0.3, back = facing < -0.3;
  switch (joint) {
    case 0:  // pelvis
      return back ? buttocks : front ? belly : torso;
    case 1:
    case 2:  // hips carry the thighs; the upper back of the thigh is buttock
      return (back && height_above_hip > -0.12) ? buttocks : thigh;
    case 3:
    case 6:  // spine1, spine2: the abdomen
      return front ? belly : torso;
    case 9:  // spine3: the chest
      return front ? chest : torso;
    case 4:
    case 5:
      return calf;
    case 12:
      return neck;
    case 15:
      return head;
    case 13:
    case 14:
      return torso;  // collars: shoulder tops
    case 16:
    case 17:
      return upper_arm;
    case 18:
    case 19:
      return forearm;
    case 20:
    case 21:
    case 22:
    case 23:
      return hand;
    case 7:
    case 8:
    case 10:
    case 11:
      return foot;
    default:
      return torso;
  }
}

std::vector<RegionMaterial> default_region_materials() {
  // Base modulus E (Pa) per region; orthotropy along : around : through =
  // 1.5 : 1 : 0.5 (fibres along the limb are stiffer), Fung scale c = 0.1 E.
  // Values within the 1e3..1e5 Pa range reported for passive soft tissue.
  const double E[] = {3e4, 8e3, 1.5e4, 1.2e4, 2e4, 3e4, 2e4, 3e4, 3e4, 1e5, 1e5, 1e5};
  std::vector<RegionMaterial> out;
  const auto& names = body_region_names();
  for (size_t i = 0; i < names.size(); ++i) {
    RegionMaterial m;
    m.name = names[i];
    m.young_along = 1.5 * E[i];
    m.young_around = E[i];
    m.young_through = 0.5 * E[i];
    m.poisson = 0.45;
    m.fung_c = 0.1 * E[i];
    m.density = 1000.0;
    out.push_back(m);
  }
  return out;
}

bool is_skinned_joint(int joint) {
  switch (joint) {
    case 7: case 8: case 10: case 11:            // ankles, feet
    case 15:                                     // head
    case 20: case 21: case 22: case 23:          // wrists, hands
      return true;
    default:
      return false;
  }
}

}  // namespace sflsh
