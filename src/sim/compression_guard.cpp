#include "sflsh/sim/compression_guard.hpp"

#include <cmath>

#include "sflsh/sim/material.hpp"

namespace sflsh {

double compression_guard(const Mat3& F, double stiffness, double onset, Mat3* dG_dF, Mat9* d2G_dF2,
                         bool project_psd) {
  const double J = F.determinant();
  if (!(J < onset)) return 0.0;
  const double gap = onset - J;       // > 0
  const double dG = -stiffness * gap;  // dG/dJ ≤ 0
  if (dG_dF || d2G_dF2) {
    const Mat3 cof = determinant_gradient(F);
    if (dG_dF) *dG_dF += dG * cof;
    if (d2G_dF2) {
      const Eigen::Map<const Vec9> gJ(cof.data());
      Mat9 H = stiffness * gJ * gJ.transpose() + dG * determinant_hessian(F);
      if (project_psd) H.diagonal().array() += -dG * std::sqrt(2.0) * F.norm();
      *d2G_dF2 += 0.5 * (H + H.transpose());
    }
  }
  return 0.5 * stiffness * gap * gap;
}

}  // namespace sflsh
