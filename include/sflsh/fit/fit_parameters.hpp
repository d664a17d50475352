#pragma once
// The parameters `sflsh fit` estimates: per region, the log of a
// factor on its three Young's moduli ("young"), the log of its Fung constant
// ("fung_c"), its Poisson's ratio ("poisson"); and the soft tissue's
// stiffness-proportional damping β ("damping", one for the body, s).
// The vector p holds them in the order of FitParameters::entries; p = 0 for
// the log-parameters is the avatar's own material. Logs keep moduli positive;
// bounds() keep every parameter in a physical range.
#include <string>
#include <vector>

#include "sflsh/asset/avatar.hpp"
#include "sflsh/sim/elastic_sensitivity.hpp"

namespace sflsh {

/// One estimated parameter.
struct FitParameter {
  enum class Kind { Young, FungC, Poisson, Damping };
  Kind kind = Kind::Young;
  int region = -1;  ///< index into avatar.materials; −1 for damping
  /// "young:belly", "fung_c:thigh", "poisson:calf", "damping".
  std::string label(const std::vector<RegionMaterial>& materials) const;
};

class FitParameters {
 public:
  /// `kinds`: comma-separated young, fung_c, poisson, damping; `regions`:
  /// "all" (every region some elastic sample lies in) or comma-separated
  /// region names of `avatar`. Throws one line naming the unknown name and the
  /// known ones.
  FitParameters(const Avatar& avatar, const std::string& kinds, const std::string& regions);

  const std::vector<FitParameter>& entries() const { return entries_; }
  int size() const { return int(entries_.size()); }
  /// The starting point: 0 for the log-parameters, the avatar's Poisson's
  /// ratio, `damping` (s) for β.
  VecX initial(const Avatar& avatar, double damping) const;
  /// Lower and upper bounds: Young's factor and Fung c in [×0.02, ×50] of the
  /// avatar's, Poisson in [0, 0.49], damping in [0, 1] s.
  void bounds(VecX& lower, VecX& upper) const;
  /// The avatar's materials with p applied (`base` = the avatar's own).
  std::vector<RegionMaterial> materials(const std::vector<RegionMaterial>& base, const VecX& p) const;
  /// β (s) of p, or `fixed` when damping is not estimated.
  double damping(const VecX& p, double fixed) const;
  /// The elastic parameters as ElasticSensitivity takes them, and for each
  /// the index of its entry in p (damping has none).
  std::vector<RegionParameter> elastic(std::vector<int>* index = nullptr) const;
  /// Whether β is estimated, and its index in p.
  int damping_index() const { return damping_index_; }
  /// The region indices estimated (increasing).
  const std::vector<int>& regions() const { return regions_; }

 private:
  std::vector<FitParameter> entries_;
  std::vector<int> regions_;
  int damping_index_ = -1;
};

}  // namespace sflsh
