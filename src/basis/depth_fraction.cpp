#include "sflsh/basis/depth_fraction.hpp"

#include <algorithm>
#include <array>
#include <vector>

#include "basis/cholmod_llt.hpp"
#include "sflsh/asset/avatar.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/fem/tet_operators.hpp"

namespace sflsh::basis {

VecXi skin_nodes(const TetMesh& mesh, const VecXi& node_role) {
  const int n = mesh.num_nodes();
  require(node_role.size() == n, "depth fraction: node_role has ", node_role.size(), " entries, expected #N = ", n);
  static const int faces[4][3] = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};
  std::vector<std::array<int, 3>> all;
  all.reserve(size_t(4 * mesh.num_elements()));
  for (int e = 0; e < mesh.num_elements(); ++e)
    for (const auto& f : faces) {
      std::array<int, 3> t{mesh.elements(e, f[0]), mesh.elements(e, f[1]), mesh.elements(e, f[2])};
      std::sort(t.begin(), t.end());
      all.push_back(t);
    }
  std::sort(all.begin(), all.end());
  std::vector<char> on_boundary(n, 0);
  for (size_t i = 0; i < all.size();) {
    size_t j = i + 1;
    while (j < all.size() && all[j] == all[i]) ++j;
    if (j - i == 1)
      for (int v : all[i]) on_boundary[v] = 1;
    i = j;
  }
  std::vector<int> out;
  for (int i = 0; i < n; ++i)
    if (on_boundary[i] && node_role[i] == int(NodeRole::Simulated)) out.push_back(i);
  return Eigen::Map<VecXi>(out.data(), Eigen::Index(out.size()));
}

VecX depth_fraction(const TetMesh& mesh, const VecXi& node_role) {
  const int n = mesh.num_nodes();
  const VecXi skin = skin_nodes(mesh, node_role);
  VecX b = VecX::Zero(n);
  for (Eigen::Index s = 0; s < skin.size(); ++s) b[skin[s]] = 1.0;
  std::vector<char> in_mesh(n, 0);
  for (int e = 0; e < mesh.num_elements(); ++e)
    for (int a = 0; a < 4; ++a) in_mesh[mesh.elements(e, a)] = 1;
  std::vector<int> free_index(n, -1), free_nodes;
  for (int i = 0; i < n; ++i)
    if (in_mesh[i] && node_role[i] == int(NodeRole::Simulated) && b[i] == 0.0)
      free_index[i] = int(free_nodes.size()), free_nodes.push_back(i);
  if (free_nodes.empty()) return b;
  // L_ff b_f = −L_fb b_b. L_ff is positive definite when every component of
  // the free nodes touches a fixed node; CHOLMOD fails (naming this) otherwise.
  const Eigen::SparseMatrix<double> L = fem::stiffness_laplacian(mesh);
  const int nf = int(free_nodes.size());
  std::vector<Eigen::Triplet<double>> trip;
  MatX rhs = MatX::Zero(nf, 1);
  for (int c = 0; c < n; ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(L, c); it; ++it) {
      const int r = free_index[it.row()];
      if (r < 0) continue;
      if (free_index[c] >= 0) {
        if (r >= free_index[c]) trip.emplace_back(r, free_index[c], it.value());
      } else {
        rhs(r, 0) -= it.value() * b[c];
      }
    }
  Eigen::SparseMatrix<double> Lff(nf, nf);
  Lff.setFromTriplets(trip.begin(), trip.end());
  detail::CholmodLLT llt;
  llt.factor(Lff, "depth fraction: harmonic system of the Simulated nodes off the skin (a part of the flesh touches "
                  "neither skin nor bone)");
  const MatX x = llt.solve(rhs);
  for (int f = 0; f < nf; ++f) b[free_nodes[f]] = std::clamp(x(f, 0), 0.0, 1.0);
  return b;
}

}  // namespace sflsh::basis
