#include "sflsh/basis/sample_handles.hpp"

#include <algorithm>
#include <vector>

#include "sflsh/core/error.hpp"

namespace sflsh::basis {

SampleHandleCounts handles_per_sample(const TetMesh& mesh, const Eigen::SparseMatrix<double, Eigen::RowMajor>& W,
                                      const VecXi& node_role, const Cubature& cubature) {
  require(W.rows() == mesh.num_nodes() && node_role.size() == mesh.num_nodes(), "handles per sample: W has ",
          W.rows(), " rows and node_role ", node_role.size(), " entries, expected #N = ", mesh.num_nodes());
  SampleHandleCounts out;
  out.samples = cubature.size();
  std::vector<int> handles;
  long total = 0;
  for (int s = 0; s < cubature.size(); ++s) {
    const int t = cubature.elements[s];
    require(t >= 0 && t < mesh.num_elements(), "handles per sample: sample ", s, " has tet ", t, ", expected in [0, ",
            mesh.num_elements(), ")");
    handles.clear();
    for (int c = 0; c < 4; ++c) {
      const int i = mesh.elements(t, c);
      if (node_role[i] != int(NodeRole::Simulated)) continue;
      for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(W, i); it; ++it)
        if (it.value() != 0.0) handles.push_back(int(it.col()));
    }
    std::sort(handles.begin(), handles.end());
    const int count = int(std::unique(handles.begin(), handles.end()) - handles.begin());
    total += count;
    out.max = std::max(out.max, count);
  }
  out.mean = out.samples > 0 ? double(total) / out.samples : 0.0;
  return out;
}

}  // namespace sflsh::basis
