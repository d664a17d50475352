#pragma once
// Material parameters as a function of body shape (seed §4: every
// shape shares one tet mesh, so a region's parameters can be interpolated):
//   p(β) = P₀ + Σ_k β_k P_k     (p as in fit_parameters.hpp: log factors, ν, β_damping),
// fitted jointly to several subjects' observations with Ceres, with the
// regularizer λ Σ_k ‖P_k‖² (the per-shape terms stay small unless the data
// asks for them), and the leave-one-subject-out surface error.
#include <memory>
#include <string>
#include <vector>

#include "sflsh/fit/material_fit.hpp"

namespace sflsh {

/// One subject: an avatar of shape β (avatar->betas), the bones that drove it
/// and its observed skin (#V by 3) at `steps`.
struct FitSubject {
  std::string name;
  std::shared_ptr<const Avatar> avatar;
  BoneSequence bones;
  std::vector<int> steps;
  std::vector<Points> observed;
};

/// The map p(β) and what it maps onto.
struct ShapeMap {
  std::vector<std::string> labels;        ///< per parameter (FitParameter::label)
  VecX p0;                                ///< P₀ (#p)
  MatX pk;                                ///< #p by #β: column k = P_k
  /// p(β) = P₀ + Σ_k β_k P_k; missing β entries count as 0, extra ones must be 0.
  VecX evaluate(const VecX& betas) const;
};

struct ShapeMapResult {
  ShapeMap map;
  std::string brief_report, termination;
  int iterations = 0;
  double seconds = 0, cpu_seconds = 0;
  /// Per subject: surface error RMS (m, vertex distance) at the starting parameters, with the joint map, and
  /// with a map fitted without it (leave-one-out; empty unless asked).
  std::vector<double> rms_before, rms_after, rms_leave_one_out;
  std::string describe(const std::vector<FitSubject>& subjects) const;
};

/// Fits the map on `subjects` (the first one's avatar names the regions; all
/// must share its tet mesh and materials' names) with regularization λ
/// (`regularization`, m² per unit² of P_k); also the leave-one-out errors when
/// `leave_one_out`. #β = the longest avatar->betas.
ShapeMapResult fit_shape_map(const std::vector<FitSubject>& subjects, const FitParameters& params,
                             const MaterialFitOptions& options, double regularization, bool leave_one_out);

/// Writes / reads a map (YAML: parameters: [{name, p0, pk: [...]}], with the
/// parameter kinds and regions in `name`). Reading throws naming the file and key.
void write_shape_map(const std::string& path, const ShapeMap& map, const std::vector<std::string>& comment = {});
ShapeMap read_shape_map(const std::string& path);

/// The avatar's materials with map(betas) applied to `params` whose labels
/// must match the map's (throws naming the first that does not), and the damping it gives (or `damping`).
std::vector<RegionMaterial> shape_map_materials(const ShapeMap& map, const Avatar& avatar, const VecX& betas,
                                                double damping, double* damping_out = nullptr);

}  // namespace sflsh
