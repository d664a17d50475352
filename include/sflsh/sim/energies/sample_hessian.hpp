#pragma once
// Assembly of one cubature sample's 9x9 block into a reduced system: the
// sample's F depends on the handles touching its tet (elastic.hpp), so
//   hess(z-block) += Gᵀ Hw G,   G(a + 3b, 3e + c) = δ_ac d_e[b]   (G = ∂vec(F)/∂z).
// Shared by the elastic term and its parameter sensitivities (elastic_sensitivity.hpp).
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "sflsh/core/types.hpp"

namespace sflsh {

/// T_e = Σ_b d_e[b] Hw(3b..3b+2, :) (3x9) for e < m: the first half of Gᵀ Hw G.
inline void sample_hessian_rows(const Eigen::Matrix<double, 9, 9>& Hw, const Vec3* d, int m,
                                std::vector<Eigen::Matrix<double, 3, 9>>& T) {
  T.resize(m);
  for (int e = 0; e < m; ++e)
    T[e] = d[e][0] * Hw.middleRows<3>(0) + d[e][1] * Hw.middleRows<3>(3) + d[e][2] * Hw.middleRows<3>(6);
}

/// Block (e, f) of Gᵀ Hw G: Σ_b' T_e(:, 3b'..3b'+2) d_f[b'] (3x3).
inline Mat3 sample_hessian_block(const Eigen::Matrix<double, 3, 9>& Te, const Vec3& df) {
  return df[0] * Te.leftCols<3>() + df[1] * Te.middleCols<3>(3) + df[2] * Te.rightCols<3>();
}

/// hess(z-block) += Gᵀ Hw G for a sample whose F depends on the handles
/// `handle[0..m)` through `d[0..m)` (1/m): with
///   T_e = Σ_b d_e[b] Hw(3b..3b+2, :)  (3x9),  block(e, f) = Σ_b' T_e(:, 3b'..) d_f[b'],
/// ~27 m² flops instead of a dense 9 by 3m product. `z0` is the first row of
/// the z block in `hess`; Hw must be symmetric (blocks (f, e) are written as
/// transposes); `T` is scratch.
inline void add_sample_hessian(const Eigen::Matrix<double, 9, 9>& Hw, const int* handle, const Vec3* d, int m, int z0,
                               Eigen::Ref<MatX> hess, std::vector<Eigen::Matrix<double, 3, 9>>& T) {
  sample_hessian_rows(Hw, d, m, T);
  for (int e = 0; e < m; ++e) {
    const int row = z0 + 3 * handle[e];
    for (int f = e; f < m; ++f) {
      const Mat3 block = sample_hessian_block(T[e], d[f]);
      const int col = z0 + 3 * handle[f];
      hess.block<3, 3>(row, col) += block;
      if (f != e) hess.block<3, 3>(col, row) += block.transpose();
    }
  }
}

/// The same sum into a K by K array of 3x3 blocks, `blocks[9 (K j + i) ..]` =
/// block (i, j) column-major, upper blocks only (i ≤ j; a block whose handles
/// come in the other order is stored transposed): each addition touches 9
/// contiguous doubles instead of three columns of the dense matrix.
/// add_hessian_blocks() adds the array to a dense matrix's both triangles.
inline void add_sample_hessian_blocks(const Eigen::Matrix<double, 9, 9>& Hw, const int* handle, const Vec3* d, int m,
                                      int K, double* blocks, std::vector<Eigen::Matrix<double, 3, 9>>& T) {
  sample_hessian_rows(Hw, d, m, T);
  for (int e = 0; e < m; ++e) {
    const int he = handle[e];
    for (int f = e; f < m; ++f) {
      const Mat3 block = sample_hessian_block(T[e], d[f]);
      const int hf = handle[f];
      if (he <= hf)
        Eigen::Map<Mat3>(blocks + 9 * (size_t(K) * hf + he)) += block;
      else
        Eigen::Map<Mat3>(blocks + 9 * (size_t(K) * he + hf)) += block.transpose();
    }
  }
}

/// add_hessian_blocks restricted to the upper blocks (i, j), i <= j, listed in
/// `used` (the others must be 0): the same sums, in the same order per entry.
inline void add_hessian_blocks(const double* blocks, int K, const std::vector<std::pair<int, int>>& used, int z0,
                               Eigen::Ref<MatX> hess) {
  for (const auto& [i, j] : used) {
    const Eigen::Map<const Mat3> B(blocks + 9 * (size_t(K) * j + i));
    if (i != j) {
      hess.block<3, 3>(z0 + 3 * i, z0 + 3 * j) += B;
      hess.block<3, 3>(z0 + 3 * j, z0 + 3 * i) += B.transpose();
      continue;
    }
    for (int c = 0; c < 3; ++c)
      for (int a = 0; a <= c; ++a) {
        hess(z0 + 3 * j + a, z0 + 3 * j + c) += B(a, c);
        if (a != c) hess(z0 + 3 * j + c, z0 + 3 * j + a) += B(a, c);
      }
  }
}

/// hess(z0.., z0..) += the symmetric matrix whose upper blocks are in `blocks`
/// (add_sample_hessian_blocks; a diagonal block's lower half is read from its upper).
inline void add_hessian_blocks(const double* blocks, int K, int z0, Eigen::Ref<MatX> hess) {
  for (int j = 0; j < K; ++j) {
    for (int i = 0; i < j; ++i) {
      const Eigen::Map<const Mat3> B(blocks + 9 * (size_t(K) * j + i));
      hess.block<3, 3>(z0 + 3 * i, z0 + 3 * j) += B;
      hess.block<3, 3>(z0 + 3 * j, z0 + 3 * i) += B.transpose();
    }
    const Eigen::Map<const Mat3> B(blocks + 9 * (size_t(K) * j + j));
    for (int c = 0; c < 3; ++c)
      for (int a = 0; a <= c; ++a) {
        hess(z0 + 3 * j + a, z0 + 3 * j + c) += B(a, c);
        if (a != c) hess(z0 + 3 * j + c, z0 + 3 * j + a) += B(a, c);
      }
  }
}

}  // namespace sflsh
