#pragma once
// Counts and quality figures of an avatar (printed by `sflsh inspect` and at the
// end of `sflsh precompute`).
#include <string>
#include <vector>

#include "sflsh/asset/avatar.hpp"
#include "sflsh/basis/basis_coverage.hpp"
#include "sflsh/basis/sample_handles.hpp"

namespace sflsh {

struct AvatarSummary {
  int surface_vertices = 0, surface_faces = 0, joints = 0;
  int tet_nodes = 0, tets = 0, simulated_nodes = 0, skinned_nodes = 0, bone_nodes = 0;
  int handles = 0, elastic_samples = 0, inertia_samples = 0, regions = 0;
  long basis_nonzeros = 0;
  double volume_m3 = 0;            ///< Σ tet volumes
  double mass_kg = 0;              ///< Σ ρ_region · tet volume
  double min_tet_volume_m3 = 0;    ///< smallest signed tet volume (must be > 0)
  double min_dihedral_deg = 0;     ///< smallest dihedral angle over all tets
  double inertia_volume_m3 = 0;    ///< Σ inertia cubature weights
  double elastic_volume_m3 = 0;    ///< Σ elastic cubature weights
  double inertia_mass_kg = 0;      ///< Σ ρ c_s over inertia samples
  double max_partition_error = 0;  ///< max over simulated nodes of (Σ_k W_nk − 1) if > 0 (must be ≤ 0)
  double min_weight = 0, max_weight = 0;
  /// Handles with a nonzero weight at each cubature sample (basis/sample_handles.hpp).
  basis::SampleHandleCounts elastic_handles, inertia_handles;
  double height_m = 0;
  /// Handles per region (by material name) and share of simulated skin nodes
  /// (outer surface, role Simulated) with Σ_k W_k ≥ 0.5.
  basis::BasisCoverage coverage;
  std::vector<std::string> region_names;
  std::string betas, model_source, model_hash;

  std::string to_text(const std::string& title) const;
  std::string to_json() const;
};

AvatarSummary summarize_avatar(const Avatar& avatar);

}  // namespace sflsh
