#pragma once
// Assembly of one cubature sample's 9x9 block into a reduced system: the
// sample's F depends on the handles touching its tet (elastic.hpp), so
//   hess(z-block) += Gᵀ Hw G,   G(a + 3b, 3e + c) = δ_ac d_e[b]   (G = ∂vec(F)/∂z).
// Shared by the elastic term and its parameter sensitivities (elastic_sensitivity.hpp).
#include <vector>

#include <Eigen/Core>

#include "sflsh/core/types.hpp"

namespace sflsh {

/// hess(z-block) += Gᵀ Hw G for a sample whose F depends on the handles
/// `handle[0..m)` through `d[0..m)` (1/m): with
///   T_e = Σ_b d_e[b] Hw(3b..3b+2, :)  (3x9),  block(e, f) = Σ_b' T_e(:, 3b'..) d_f[b'],
/// ~27 m² flops instead of a dense 9 by 3m product. `z0` is the first row of
/// the z block in `hess`; Hw must be symmetric; `T` is scratch.
/// kUpperOnly = false: blocks (f, e) are written as transposes (both triangles).
/// kUpperOnly = true: each block goes only to the upper of its two positions
/// (row ≤ col), the diagonal blocks whole; the caller mirrors the upper
/// triangle (ElasticTerm: about half the scattered writes).
template <bool kUpperOnly = false>
inline void add_sample_hessian(const Eigen::Matrix<double, 9, 9>& Hw, const int* handle, const Vec3* d, int m, int z0,
                               Eigen::Ref<MatX> hess, std::vector<Eigen::Matrix<double, 3, 9>>& T) {
  T.resize(m);
  for (int e = 0; e < m; ++e)
    T[e] = d[e][0] * Hw.middleRows<3>(0) + d[e][1] * Hw.middleRows<3>(3) + d[e][2] * Hw.middleRows<3>(6);
  for (int e = 0; e < m; ++e) {
    const int row = z0 + 3 * handle[e];
    for (int f = e; f < m; ++f) {
      const Mat3 block = d[f][0] * T[e].leftCols<3>() + d[f][1] * T[e].middleCols<3>(3) + d[f][2] * T[e].rightCols<3>();
      const int col = z0 + 3 * handle[f];
      if constexpr (kUpperOnly) {
        if (row <= col)
          hess.block<3, 3>(row, col) += block;
        else
          hess.block<3, 3>(col, row) += block.transpose();
      } else {
        hess.block<3, 3>(row, col) += block;
        if (f != e) hess.block<3, 3>(col, row) += block.transpose();
      }
    }
  }
}

}  // namespace sflsh
