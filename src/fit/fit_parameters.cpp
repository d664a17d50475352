#include "sflsh/fit/fit_parameters.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "sflsh/core/error.hpp"
#include "sflsh/sim/elastic_sensitivity.hpp"

namespace sflsh {
namespace {

std::vector<std::string> split_list(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream in(s);
  std::string item;
  while (std::getline(in, item, ',')) {
    item.erase(0, item.find_first_not_of(" \t"));
    item.erase(item.find_last_not_of(" \t") + 1);
    if (!item.empty()) out.push_back(item);
  }
  return out;
}

constexpr double kLogFactorRange = 3.912023005428146;  // log 50

}  // namespace

std::string FitParameter::label(const std::vector<RegionMaterial>& materials) const {
  switch (kind) {
    case Kind::Young: return "young:" + materials.at(region).name;
    case Kind::FungC: return "fung_c:" + materials.at(region).name;
    case Kind::Poisson: return "poisson:" + materials.at(region).name;
    case Kind::Damping: return "damping";
  }
  return "";
}

FitParameters::FitParameters(const Avatar& a, const std::string& kinds, const std::string& regions) {
  require(!a.materials.empty(), "fit: the avatar has no materials");
  const std::vector<std::string> kind_names = split_list(kinds);
  require(!kind_names.empty(), "--params: give at least one of young, fung_c, poisson, damping");
  std::vector<FitParameter::Kind> ks;
  bool damping = false;
  for (const std::string& k : kind_names) {
    FitParameter::Kind kind;
    if (k == "young") kind = FitParameter::Kind::Young;
    else if (k == "fung_c") kind = FitParameter::Kind::FungC;
    else if (k == "poisson") kind = FitParameter::Kind::Poisson;
    else if (k == "damping") kind = FitParameter::Kind::Damping;
    else fail("--params: unknown parameter '", k, "' (expected young, fung_c, poisson, damping)");
    require(std::find(ks.begin(), ks.end(), kind) == ks.end(), "--params: '", k, "' given twice");
    ks.push_back(kind);
    damping = damping || kind == FitParameter::Kind::Damping;
  }
  // Regions some elastic sample lies in: the others do not change the simulation.
  std::vector<bool> used(a.materials.size(), false);
  for (int k = 0; k < a.elastic.size(); ++k)
    used[a.tet_region.size() ? a.tet_region[a.elastic.elements[k]] : 0] = true;
  const std::vector<std::string> region_names = split_list(regions);
  require(!region_names.empty(), "--regions: give 'all' or region names");
  std::string known;
  for (size_t r = 0; r < a.materials.size(); ++r)
    if (used[r]) known += (known.empty() ? "" : ", ") + a.materials[r].name;
  if (region_names.size() == 1 && region_names[0] == "all") {
    for (size_t r = 0; r < a.materials.size(); ++r)
      if (used[r]) regions_.push_back(int(r));
  } else {
    for (const std::string& n : region_names) {
      auto it = std::find_if(a.materials.begin(), a.materials.end(), [&](const RegionMaterial& m) { return m.name == n; });
      require(it != a.materials.end(), "--regions: unknown region '", n, "' (this avatar's simulated regions: ", known, ")");
      const int r = int(it - a.materials.begin());
      require(used[r], "--regions: region '", n, "' has no elastic cubature sample, so its material does not act (simulated regions: ",
              known, ")");
      require(std::find(regions_.begin(), regions_.end(), r) == regions_.end(), "--regions: '", n, "' given twice");
      regions_.push_back(r);
    }
    std::sort(regions_.begin(), regions_.end());
  }
  for (int r : regions_)
    for (FitParameter::Kind k : ks)
      if (k != FitParameter::Kind::Damping) entries_.push_back({k, r});
  if (damping) {
    damping_index_ = int(entries_.size());
    entries_.push_back({FitParameter::Kind::Damping, -1});
  }
}

VecX FitParameters::initial(const Avatar& a, double damping) const {
  VecX p = VecX::Zero(size());
  for (int i = 0; i < size(); ++i) {
    if (entries_[i].kind == FitParameter::Kind::Poisson) p[i] = a.materials[entries_[i].region].poisson;
    if (entries_[i].kind == FitParameter::Kind::Damping) p[i] = damping;
  }
  return p;
}

void FitParameters::bounds(VecX& lower, VecX& upper) const {
  lower.resize(size());
  upper.resize(size());
  for (int i = 0; i < size(); ++i) {
    switch (entries_[i].kind) {
      case FitParameter::Kind::Young:
      case FitParameter::Kind::FungC: lower[i] = -kLogFactorRange, upper[i] = kLogFactorRange; break;
      case FitParameter::Kind::Poisson: lower[i] = 0.0, upper[i] = 0.49; break;
      case FitParameter::Kind::Damping: lower[i] = 0.0, upper[i] = 1.0; break;
    }
  }
}

std::vector<RegionMaterial> FitParameters::materials(const std::vector<RegionMaterial>& base, const VecX& p) const {
  require(p.size() == size(), "fit: ", p.size(), " parameter values for ", size(), " parameters");
  std::vector<RegionMaterial> m = base;
  for (int i = 0; i < size(); ++i) {
    const FitParameter& e = entries_[i];
    if (e.kind == FitParameter::Kind::Damping) continue;
    RegionMaterial& r = m.at(e.region);
    const RegionMaterial& b = base.at(e.region);
    if (e.kind == FitParameter::Kind::Young) {
      r.young_along = b.young_along, r.young_through = b.young_through, r.young_around = b.young_around;
      r = perturbed_material(r, MaterialParameter::LogYoung, p[i]);  // the base's moduli times e^p
    } else if (e.kind == FitParameter::Kind::FungC) {
      r.fung_c = b.fung_c;
      r = perturbed_material(r, MaterialParameter::LogFungC, p[i]);  // the base's Fung c times e^p
    } else {
      r.poisson = p[i];
    }
  }
  return m;
}

double FitParameters::damping(const VecX& p, double fixed) const {
  return damping_index_ >= 0 ? p[damping_index_] : fixed;
}

std::vector<RegionParameter> FitParameters::elastic(std::vector<int>* index) const {
  std::vector<RegionParameter> out;
  if (index) index->clear();
  for (int i = 0; i < size(); ++i) {
    const FitParameter& e = entries_[i];
    if (e.kind == FitParameter::Kind::Damping) continue;
    out.push_back({e.region, e.kind == FitParameter::Kind::Young   ? MaterialParameter::LogYoung
                             : e.kind == FitParameter::Kind::FungC ? MaterialParameter::LogFungC
                                                                   : MaterialParameter::Poisson});
    if (index) index->push_back(i);
  }
  return out;
}

}  // namespace sflsh
