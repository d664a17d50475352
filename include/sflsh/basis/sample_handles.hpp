#pragma once
// How local the reduced basis is at the cubature samples: the number of
// handles whose weight is nonzero at a sample (at any Simulated node of its
// tet). It is the size of the sample's block in the reduced gradient and
// Hessian, so it sets the cost of assembling them.
#include <Eigen/Sparse>

#include "sflsh/asset/avatar.hpp"

namespace sflsh::basis {

struct SampleHandleCounts {
  double mean = 0.0;  ///< over samples
  int max = 0;
  int samples = 0;
};

/// Handles per sample of `cubature` for the basis W (#N by #K); nodes whose
/// role is not Simulated carry no soft displacement and are skipped.
SampleHandleCounts handles_per_sample(const TetMesh& mesh, const Eigen::SparseMatrix<double, Eigen::RowMajor>& W,
                                      const VecXi& node_role, const Cubature& cubature);

}  // namespace sflsh::basis
