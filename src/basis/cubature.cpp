#include "sflsh/basis/cubature.hpp"

#include <map>
#include <vector>

#include "sflsh/fem/tet_operators.hpp"
#include "sflsh/core/error.hpp"
#include "farthest_points.hpp"

namespace sflsh::basis {

Cubature data_oblivious_cubature(const TetMesh& mesh, const Eigen::SparseMatrix<double, Eigen::RowMajor>& W,
                                 const VecXi& handle_nodes, const VecXi& dominant_bone) {
  const int n = mesh.num_nodes(), T = mesh.num_elements(), K = int(handle_nodes.size());
  require(W.rows() == n && W.cols() == K, "cubature: W is ", W.rows(), " by ", W.cols(), ", expected #N by #K = ", n,
          " by ", K);
  require(dominant_bone.size() == 0 || dominant_bone.size() == n, "cubature: dominant_bone has ",
          dominant_bone.size(), " entries, expected #N = ", n, " or none");
  const VecX vol = fem::tet_volumes(mesh);

  // Largest incident tet and local vertex index for every handle node.
  std::vector<int> handle_of(n, -1);
  for (int k = 0; k < K; ++k) {
    require(handle_nodes(k) >= 0 && handle_nodes(k) < n, "cubature: handle ", k, " node ", handle_nodes(k),
            " out of range");
    handle_of[handle_nodes(k)] = k;
  }
  std::vector<int> tet_of(K, -1), corner_of(K, -1);
  for (int e = 0; e < T; ++e)
    for (int a = 0; a < 4; ++a) {
      const int k = handle_of[mesh.elements(e, a)];
      if (k >= 0 && (tet_of[k] < 0 || vol(e) > vol(tet_of[k]))) tet_of[k] = e, corner_of[k] = a;
    }

  // Integrals of the handle weights and of the bone complement per region.
  const MatX Wd = MatX(W);
  const Eigen::RowVectorXd c_handles = fem::integrate_linear(mesh, Wd);
  VecX bone = VecX::Ones(n) - Wd.rowwise().sum();
  std::map<int, int> region_col;  // bone index → column
  for (int i = 0; i < n; ++i) region_col.emplace(dominant_bone.size() ? dominant_bone(i) : 0, 0);
  region_col.erase(-1);  // −1: no bone (only allowed where w_bone = 0, checked below)
  int col = 0;
  for (auto& rc : region_col) rc.second = col++;
  MatX bone_fields = MatX::Zero(n, col);
  for (int i = 0; i < n; ++i) {
    const int b = dominant_bone.size() ? dominant_bone(i) : 0;
    if (b < 0) {
      require(std::abs(bone(i)) < 1e-12, "cubature: node ", i, " has no dominant bone but bone weight ", bone(i));
      continue;
    }
    bone_fields(i, region_col[b]) = bone(i);
  }
  const Eigen::RowVectorXd c_bones = fem::integrate_linear(mesh, bone_fields);

  std::vector<int> elems;
  std::vector<Eigen::RowVector4d> barys;
  std::vector<double> weights;
  for (int k = 0; k < K; ++k) {
    require(tet_of[k] >= 0, "cubature: handle ", k, " node ", handle_nodes(k), " belongs to no tet");
    Eigen::RowVector4d b = Eigen::RowVector4d::Zero();
    b(corner_of[k]) = 1.0;
    elems.push_back(tet_of[k]);
    barys.push_back(b);
    weights.push_back(c_handles(k));
  }
  for (int c = 0; c < col; ++c) {
    if (c_bones(c) <= 0.0) continue;
    int best = -1;
    double best_mean = -1.0;
    for (int e = 0; e < T; ++e) {
      double mean = 0.0;
      for (int a = 0; a < 4; ++a) mean += 0.25 * bone_fields(mesh.elements(e, a), c);
      if (mean > best_mean) best_mean = mean, best = e;
    }
    elems.push_back(best);
    barys.push_back(Eigen::RowVector4d::Constant(0.25));
    weights.push_back(c_bones(c));
  }

  Cubature cub;
  const int S = int(elems.size());
  cub.elements.resize(S);
  cub.barycentric.resize(S, 4);
  cub.weights.resize(S);
  for (int s = 0; s < S; ++s) {
    cub.elements(s) = elems[s];
    cub.barycentric.row(s) = barys[s];
    cub.weights(s) = weights[s];
  }
  return cub;
}

Cubature stratified_cubature(const TetMesh& mesh, const Eigen::SparseMatrix<double, Eigen::RowMajor>& W,
                             const VecXi& dominant_bone, int samples_per_cell) {
  require(samples_per_cell >= 1, "stratified_cubature: samples_per_cell must be >= 1");
  require(W.rows() == mesh.num_nodes(), "stratified_cubature: W has ", W.rows(), " rows, mesh has ", mesh.num_nodes(),
          " nodes");
  const int K = int(W.cols());
  const VecX vol = fem::tet_volumes(mesh);
  // Node-wise weights of the K handles plus the bone complement.
  MatX Wd = MatX(W);
  // Cell label per tet: argmax of the tet-mean weights; bone cells by bone index.
  std::map<int, std::vector<int>> cells;
  for (int t = 0; t < mesh.num_elements(); ++t) {
    Eigen::RowVectorXd mean = Eigen::RowVectorXd::Zero(K);
    for (int c = 0; c < 4; ++c) mean += Wd.row(mesh.elements(t, c));
    mean /= 4.0;
    int k = 0;
    const double best = K > 0 ? mean.maxCoeff(&k) : 0.0;
    const double bone = 1.0 - mean.sum();
    const int label = (K == 0 || bone > best)
                          ? K + (dominant_bone.size() ? dominant_bone[mesh.elements(t, 0)] : 0)
                          : k;
    cells[label].push_back(t);
  }
  Cubature out;
  std::vector<int> elems;
  std::vector<double> weights;
  for (const auto& [label, tets] : cells) {
    double cell_volume = 0;
    for (int t : tets) cell_volume += vol[t];
    Points centroid(tets.size(), 3);
    for (size_t i = 0; i < tets.size(); ++i) {
      Vec3 c = Vec3::Zero();
      for (int n = 0; n < 4; ++n) c += mesh.nodes.row(mesh.elements(tets[i], n)).transpose();
      centroid.row(i) = c / 4.0;
    }
    // Farthest-point sampling from the cell's centroid-nearest tet.
    const int m = std::min<int>(samples_per_cell, int(tets.size()));
    const std::vector<int> chosen = farthest_points(centroid, m);
    for (int i : chosen) {
      elems.push_back(tets[i]);
      weights.push_back(cell_volume / m);
    }
  }
  out.elements = Eigen::Map<VecXi>(elems.data(), elems.size());
  out.weights = Eigen::Map<VecX>(weights.data(), weights.size());
  out.barycentric = MatXr::Constant(elems.size(), 4, 0.25);
  return out;
}

Cubature full_cubature(const TetMesh& mesh, const VecXi& node_role, bool simulated_only) {
  std::vector<int> keep;
  for (int t = 0; t < mesh.num_elements(); ++t) {
    bool any_simulated = !simulated_only || node_role.size() == 0;
    for (int c = 0; c < 4 && !any_simulated; ++c)
      any_simulated = node_role[mesh.elements(t, c)] == int(NodeRole::Simulated);
    if (any_simulated) keep.push_back(t);
  }
  Cubature cub;
  cub.elements.resize(Eigen::Index(keep.size()));
  cub.barycentric = MatXr::Constant(Eigen::Index(keep.size()), 4, 0.25);
  cub.weights.resize(Eigen::Index(keep.size()));
  for (size_t i = 0; i < keep.size(); ++i) {
    const int t = keep[i];
    const Vec3 x0 = mesh.nodes.row(mesh.elements(t, 0)).transpose();
    Mat3 D;
    for (int c = 1; c < 4; ++c) D.col(c - 1) = mesh.nodes.row(mesh.elements(t, c)).transpose() - x0;
    cub.elements[Eigen::Index(i)] = t;
    cub.weights[Eigen::Index(i)] = std::abs(D.determinant()) / 6.0;
  }
  return cub;
}

Cubature nodal_cubature(const TetMesh& mesh, const VecX& tet_density, const VecXi& node_role) {
  const int T = mesh.num_elements(), N = mesh.num_nodes();
  require(tet_density.size() == 0 || tet_density.size() == T, "nodal_cubature: tet_density has ", tet_density.size(),
          " entries, expected #T = ", T);
  require(node_role.size() == 0 || node_role.size() == N, "nodal_cubature: node_role has ", node_role.size(),
          " entries, expected #N = ", N);
  const VecX volume = fem::tet_volumes(mesh);
  VecX mass = VecX::Zero(N);
  std::vector<int> first_tet(size_t(N), -1), corner(size_t(N), -1);
  std::vector<char> keep(size_t(N), node_role.size() == 0 ? 1 : 0);
  for (int t = 0; t < T; ++t) {
    const double rho = tet_density.size() ? tet_density[t] : 1.0;
    bool any_simulated = false;
    for (int c = 0; c < 4; ++c) any_simulated |= node_role.size() && node_role[mesh.elements(t, c)] == int(NodeRole::Simulated);
    for (int c = 0; c < 4; ++c) {
      const int n = mesh.elements(t, c);
      mass[n] += rho * volume[t] / 4.0;
      if (any_simulated) keep[size_t(n)] = 1;
      if (first_tet[size_t(n)] < 0) first_tet[size_t(n)] = t, corner[size_t(n)] = c;
    }
  }
  std::vector<int> nodes;
  for (int n = 0; n < N; ++n)
    if (keep[size_t(n)] && first_tet[size_t(n)] >= 0) nodes.push_back(n);
  Cubature cub;
  const Eigen::Index S = Eigen::Index(nodes.size());
  cub.elements.resize(S);
  cub.barycentric = MatXr::Zero(S, 4);
  cub.weights.resize(S);
  for (Eigen::Index s = 0; s < S; ++s) {
    const int n = nodes[size_t(s)], t = first_tet[size_t(n)];
    cub.elements[s] = t;
    cub.barycentric(s, corner[size_t(n)]) = 1.0;
    cub.weights[s] = mass[n] / (tet_density.size() ? tet_density[t] : 1.0);
  }
  return cub;
}

Points cubature_points(const TetMesh& mesh, const Cubature& cubature) {
  Points p(cubature.size(), 3);
  for (int s = 0; s < cubature.size(); ++s) {
    const int e = cubature.elements(s);
    require(e >= 0 && e < mesh.num_elements(), "cubature: sample ", s, " refers to tet ", e, ", expected 0..",
            mesh.num_elements() - 1);
    p.row(s).setZero();
    for (int a = 0; a < 4; ++a) p.row(s) += cubature.barycentric(s, a) * mesh.nodes.row(mesh.elements(e, a));
  }
  return p;
}

CubatureErrors cubature_errors(const TetMesh& mesh, const Cubature& cubature, const VecX& tet_density) {
  const int T = mesh.num_elements();
  require(tet_density.size() == 0 || tet_density.size() == T, "cubature errors: tet_density has ",
          tet_density.size(), " entries, expected #T = ", T, " or none");
  const VecX rho = tet_density.size() ? tet_density : VecX::Constant(T, 1000.0);
  const VecX vol = fem::tet_volumes(mesh);
  Vec3 c = Vec3::Zero();
  std::vector<Vec3> g(T);
  for (int e = 0; e < T; ++e) {
    g[e] = Vec3::Zero();
    for (int a = 0; a < 4; ++a) g[e] += 0.25 * mesh.nodes.row(mesh.elements(e, a)).transpose();
    c += vol(e) * g[e];
  }
  c /= vol.sum();

  CubatureErrors r;
  for (int e = 0; e < T; ++e) {
    r.volume_full += vol(e);
    r.mass_full += rho(e) * vol(e);
    double second = 0.0;
    for (int a = 0; a < 4; ++a) second += (mesh.nodes.row(mesh.elements(e, a)).transpose() - g[e]).squaredNorm();
    r.quadratic_full += vol(e) * ((g[e] - c).squaredNorm() + second / 20.0);
  }
  const Points x = cubature_points(mesh, cubature);
  for (int s = 0; s < cubature.size(); ++s) {
    r.volume_cubature += cubature.weights(s);
    r.mass_cubature += cubature.weights(s) * rho(cubature.elements(s));
    r.quadratic_cubature += cubature.weights(s) * (x.row(s).transpose() - c).squaredNorm();
  }
  r.volume_error = (r.volume_cubature - r.volume_full) / r.volume_full;
  r.mass_error = (r.mass_cubature - r.mass_full) / r.mass_full;
  r.quadratic_error = (r.quadratic_cubature - r.quadratic_full) / r.quadratic_full;
  return r;
}

}  // namespace sflsh::basis
