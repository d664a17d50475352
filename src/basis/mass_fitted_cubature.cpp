#include "sflsh/basis/mass_fitted_cubature.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>
#include <vector>

#include "farthest_points.hpp"
#include "nonnegative_least_squares.hpp"
#include "sflsh/basis/cubature.hpp"
#include "sflsh/core/error.hpp"

namespace sflsh::basis {
namespace {

using Features = std::vector<std::pair<int, double>>;  // (field index, value), sorted by index
using RowSparse = Eigen::SparseMatrix<double, Eigen::RowMajor>;

/// Lumped nodal masses of every node (nodal_cubature), one sample per node:
/// the reference's mass model for the flesh, and the mass of the tissue that
/// only the bones carry (it adds to their inertia when bones are dynamic).
struct NodeMasses {
  Cubature lumped;
  VecX mass;                   ///< per mesh node
  std::vector<int> nodes;      ///< the nodes with a sample, in sample order
  std::vector<int> sample_of;  ///< per mesh node: its sample, or −1
};

NodeMasses node_masses(const TetMesh& mesh, const VecX& tet_density) {
  const int N = mesh.num_nodes();
  NodeMasses m{nodal_cubature(mesh, tet_density), VecX::Zero(N), {}, std::vector<int>(size_t(N), -1)};
  for (int s = 0; s < m.lumped.size(); ++s) {
    int corner = 0;
    m.lumped.barycentric.row(s).maxCoeff(&corner);
    const int t = m.lumped.elements[s], n = mesh.elements(t, corner);
    m.mass[n] = tet_density[t] * m.lumped.weights[s];
    m.nodes.push_back(n);
    m.sample_of[size_t(n)] = s;
  }
  return m;
}

/// Each node's fields (K + 4B of them): its handle weights (Simulated nodes),
/// and per bone b its weight and the weight times its offset from the bone
/// centroid c_b.
std::vector<Features> node_fields(const TetMesh& mesh, const RowSparse& W, const VecXi& node_role,
                                  const MatXr& node_weights, const NodeMasses& m) {
  const int K = int(W.cols()), B = int(node_weights.cols());
  const VecX& mass = m.mass;
  const std::vector<int>& nodes = m.nodes;
  Points centroid = Points::Zero(B, 3);
  VecX bone_mass = VecX::Zero(B);
  for (int n : nodes)
    for (int b = 0; b < B; ++b) {
      bone_mass[b] += mass[n] * node_weights(n, b);
      centroid.row(b) += mass[n] * node_weights(n, b) * mesh.nodes.row(n);
    }
  for (int b = 0; b < B; ++b)
    if (bone_mass[b] > 0) centroid.row(b) /= bone_mass[b];
  auto features = [&](int n) {
    Features f;
    if (node_role[n] == int(NodeRole::Simulated))
      for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(W, n); it; ++it)
        if (it.value() != 0) f.emplace_back(int(it.col()), it.value());
    for (int b = 0; b < B; ++b) {
      const double w = node_weights(n, b);
      if (w == 0) continue;
      f.emplace_back(K + 4 * b, w);
      for (int i = 0; i < 3; ++i) f.emplace_back(K + 4 * b + 1 + i, w * (mesh.nodes(n, i) - centroid(b, i)));
    }
    std::sort(f.begin(), f.end());
    return f;
  };
  std::vector<Features> field(nodes.size());
  for (size_t i = 0; i < nodes.size(); ++i) field[i] = features(nodes[i]);
  return field;
}

/// The moments M_ab (a ≤ b) of the F fields over the nodes, and the equation
/// row of each (−1: none; rows need both fields' M_aa > 0).
struct Moments {
  int F = 0, rows = 0;
  std::vector<double> moment;  ///< F × F, row a, column b
  std::vector<int> row_of;     ///< F × F
  /// 1 / sqrt(M_aa M_bb): the normalization of row (a, b).
  double pair_scale(int a, int b) const { return 1.0 / std::sqrt(moment[size_t(a) * F + a] * moment[size_t(b) * F + b]); }
};

Moments field_moments(const std::vector<Features>& field, const NodeMasses& m, int F) {
  const VecX& mass = m.mass;
  const std::vector<int>& nodes = m.nodes;
  Moments out;
  out.F = F;
  std::vector<double>& moment = out.moment;
  moment.assign(size_t(F) * F, 0.0);
  std::vector<char> used(size_t(F) * F, 0);
  for (size_t i = 0; i < nodes.size(); ++i) {
    const Features& f = field[i];
    for (size_t p = 0; p < f.size(); ++p)
      for (size_t q = p; q < f.size(); ++q) {
        const size_t key = size_t(f[p].first) * F + f[q].first;
        moment[key] += mass[nodes[i]] * f[p].second * f[q].second;
        used[key] = 1;
      }
  }
  std::vector<int>& row_of = out.row_of;
  row_of.assign(size_t(F) * F, -1);
  int& rows = out.rows;
  for (size_t key = 0; key < used.size(); ++key)
    if (used[key] && moment[size_t(key / F) * F + key / F] > 0 && moment[size_t(key % F) * F + key % F] > 0)
      row_of[key] = rows++;
  return out;
}

/// Candidates (indices into m.nodes): per cell (the node's dominant handle,
/// else its dominant bone), farthest-point nodes; initial mass = cell mass / count.
void cell_candidates(const TetMesh& mesh, const RowSparse& W, const VecXi& node_role, const MatXr& node_weights,
                     const NodeMasses& m, int samples_per_cell, std::vector<int>* candidate_out,
                     std::vector<double>* initial_out) {
  const int K = int(W.cols());
  const VecX& mass = m.mass;
  const std::vector<int>& nodes = m.nodes;
  std::vector<int>& candidate = *candidate_out;
  std::vector<double>& initial = *initial_out;
  std::map<int, std::vector<int>> cells;  // label -> indices into `nodes`
  for (size_t i = 0; i < nodes.size(); ++i) {
    const int n = nodes[i];
    int label = -1;
    if (node_role[n] == int(NodeRole::Simulated) && K > 0) {
      double best = 0, sum = 0;
      for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(W, n); it; ++it) {
        sum += it.value();
        if (it.value() > best) best = it.value(), label = int(it.col());
      }
      if (1.0 - sum > best) label = -1;
    }
    if (label < 0) {
      int b = 0;
      node_weights.row(n).maxCoeff(&b);
      label = K + b;
    }
    cells[label].push_back(int(i));
  }
  for (const auto& [label, members] : cells) {
    Points p(Eigen::Index(members.size()), 3);
    double cell_mass = 0;
    for (size_t j = 0; j < members.size(); ++j) {
      p.row(Eigen::Index(j)) = mesh.nodes.row(nodes[size_t(members[j])]);
      cell_mass += mass[nodes[size_t(members[j])]];
    }
    const std::vector<int> chosen = farthest_points(p, samples_per_cell);
    for (int j : chosen) {
      candidate.push_back(members[size_t(j)]);
      initial.push_back(cell_mass / double(chosen.size()));
    }
  }
}

}  // namespace

Cubature mass_fitted_cubature(const TetMesh& mesh, const Eigen::SparseMatrix<double, Eigen::RowMajor>& W,
                              const VecXi& node_role, const MatXr& node_weights, const VecX& tet_density,
                              int samples_per_cell, MassFitReport* report) {
  const int N = mesh.num_nodes(), T = mesh.num_elements(), K = int(W.cols()), B = int(node_weights.cols());
  require(samples_per_cell >= 1, "mass_fitted_cubature: samples_per_cell must be >= 1, got ", samples_per_cell);
  require(W.rows() == N, "mass_fitted_cubature: W has ", W.rows(), " rows, mesh has ", N, " nodes");
  require(node_role.size() == N, "mass_fitted_cubature: node_role has ", node_role.size(), " entries, expected ", N);
  require(node_weights.rows() == N && B > 0, "mass_fitted_cubature: node_weights is ", node_weights.rows(), " by ", B,
          ", expected ", N, " by #bones");
  require(tet_density.size() == T, "mass_fitted_cubature: tet_density has ", tet_density.size(), " entries, expected ",
          T);

  const NodeMasses masses = node_masses(mesh, tet_density);
  const Cubature& lumped = masses.lumped;
  const VecX& mass = masses.mass;
  const std::vector<int>& nodes = masses.nodes;
  const std::vector<int>& sample_of = masses.sample_of;
  require(!nodes.empty(), "mass_fitted_cubature: the mesh has no tets");

  // Each node's fields, their moments and the equation rows.
  const int F = K + 4 * B;
  const std::vector<Features> field = node_fields(mesh, W, node_role, node_weights, masses);
  const Moments moments = field_moments(field, masses, F);
  const std::vector<double>& moment = moments.moment;
  const std::vector<int>& row_of = moments.row_of;
  const int rows = moments.rows;
  auto pair_scale = [&](int a, int b) { return moments.pair_scale(a, b); };

  std::vector<int> candidate;  // indices into `nodes`
  std::vector<double> initial;
  cell_candidates(mesh, W, node_role, node_weights, masses, samples_per_cell, &candidate, &initial);
  const int n = int(candidate.size());

  // Equations A c = b: the normalized moment rows, then the total mass (weight 3).
  const double total_mass = [&] {
    double m = 0;
    for (int node : nodes) m += mass[node];
    return m;
  }();
  constexpr double kMassRowWeight = 30.0;
  VecX b = VecX::Zero(rows + 1);
  for (size_t key = 0; key < row_of.size(); ++key)
    if (row_of[key] >= 0) b[row_of[key]] = pair_scale(int(key / F), int(key % F)) * moment[key];
  b[rows] = kMassRowWeight;
  std::vector<Eigen::Triplet<double>> entries;
  for (int s = 0; s < n; ++s) {
    const Features& f = field[size_t(candidate[size_t(s)])];
    for (size_t p = 0; p < f.size(); ++p)
      for (size_t q = p; q < f.size(); ++q) {
        const int row = row_of[size_t(f[p].first) * F + f[q].first];
        if (row >= 0) entries.emplace_back(row, s, pair_scale(f[p].first, f[q].first) * f[p].second * f[q].second);
      }
    entries.emplace_back(rows, s, kMassRowWeight / total_mass);
  }
  Eigen::SparseMatrix<double> A(rows + 1, n);
  A.setFromTriplets(entries.begin(), entries.end());
  const MatX Q = MatX(A.transpose() * A);
  const VecX f = A.transpose() * b;
  VecX c = Eigen::Map<const VecX>(initial.data(), n);
  const double bnorm = b.head(rows).norm();
  const double initial_error = (A * c - b).head(rows).norm() / bnorm;
  const int sweeps = nonnegative_least_squares(Q, f, c, 20000);

  std::vector<int> kept;
  for (int s = 0; s < n; ++s)
    if (c[s] > 1e-9 * c.maxCoeff()) kept.push_back(s);
  Cubature out;
  const Eigen::Index S = Eigen::Index(kept.size());
  out.elements.resize(S);
  out.barycentric = MatXr::Zero(S, 4);
  out.weights.resize(S);
  for (Eigen::Index i = 0; i < S; ++i) {
    const int s = kept[size_t(i)], sample = sample_of[size_t(nodes[size_t(candidate[size_t(s)])])];
    const int t = lumped.elements[sample];
    out.elements[i] = t;
    out.barycentric.row(i) = lumped.barycentric.row(sample);
    out.weights[i] = c[s] / tet_density[t];
  }
  if (report) {
    report->candidates = n;
    report->samples = int(S);
    report->sweeps = sweeps;
    report->moments = rows;
    report->moment_error_initial = initial_error;
    report->moment_error = (A * c - b).head(rows).norm() / bnorm;
    report->mass = total_mass;
    report->mass_error = (c.sum() - total_mass) / total_mass;
  }
  return out;
}

}  // namespace sflsh::basis
