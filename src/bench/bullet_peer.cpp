#include "sflsh/bench/bullet_peer.hpp"

#include <cmath>
#include <limits>

#include <BulletSoftBody/btDeformableBodySolver.h>
#include <BulletSoftBody/btDeformableGravityForce.h>
#include <BulletSoftBody/btDeformableMultiBodyConstraintSolver.h>
#include <BulletSoftBody/btDeformableMultiBodyDynamicsWorld.h>
#include <BulletSoftBody/btDeformableNeoHookeanForce.h>
#include <BulletSoftBody/btSoftBody.h>
#include <BulletSoftBody/btSoftBodyRigidBodyCollisionConfiguration.h>
#include <btBulletDynamicsCommon.h>

#include "sflsh/core/error.hpp"
#include "sflsh/core/timer.hpp"
#include "sflsh/sim/energies/elastic.hpp"

namespace sflsh {

LameParameters isotropic_equivalent(const RegionMaterial& m) {
  m.require_in_range();
  const double nu = m.poisson;
  const double E[3] = {m.young_along, m.young_through, m.young_around};
  const double a = 1.0 / (1 + nu), b = nu / ((1 + nu) * (1 - 2 * nu));
  const double diag = (a + b) * (E[0] + E[1] + E[2]);                                               // Σ C_ii
  const double cross = std::sqrt(E[0] * E[1]) + std::sqrt(E[0] * E[2]) + std::sqrt(E[1] * E[2]);  // Σ_{i<j} √(E_iE_j)
  const double K = (diag + 2 * b * cross) / 9.0;
  const double G = (diag - b * cross + 3 * (0.5 * a * cross)) / 15.0;
  return {G, K - 2.0 * G / 3.0};
}

LameParameters neo_hookean_lame(const LameParameters& s) { return {4.0 / 3.0 * s.mu, s.lambda + 5.0 / 6.0 * s.mu}; }

namespace {

/// Bullet's deformable solver with its Newton settings readable.
struct PeerSolver : btDeformableBodySolver {
  int newton_iterations() const { return m_maxNewtonIterations; }
  void set_newton_iterations(int n) { m_maxNewtonIterations = n; }
};

btVector3 bt(const Vec3& v) { return btVector3(v.x(), v.y(), v.z()); }

/// Skinned rest position Σ_j w_nj G_j x̄_n of node n (m, world).
Vec3 skinned_node(const Avatar& a, int n, const std::vector<Isometry>& bones) {
  const Vec3 y = a.tet.nodes.row(n).transpose();
  Vec3 s = Vec3::Zero();
  for (int j = 0; j < 24; ++j)
    if (a.node_weights(n, j) != 0.0) s += a.node_weights(n, j) * (bones[size_t(j)] * y);
  return s;
}

}  // namespace

struct BulletPeer::World {
  btSoftBodyRigidBodyCollisionConfiguration configuration;
  btCollisionDispatcher dispatcher{&configuration};
  btDbvtBroadphase broadphase;
  PeerSolver solver;
  btDeformableMultiBodyConstraintSolver constraint_solver;
  std::unique_ptr<btDeformableMultiBodyDynamicsWorld> world;
  std::unique_ptr<btSoftBody> body;
  std::unique_ptr<btDeformableNeoHookeanForce> elastic;
  std::unique_ptr<btDeformableGravityForce> gravity;
  ~World() {
    if (world && body) world->removeSoftBody(body.get());
  }
};

BulletPeer::BulletPeer(std::shared_ptr<const Avatar> avatar, BulletPeerOptions options)
    : avatar_(std::move(avatar)), options_(options), world_(std::make_unique<World>()) {
  require(avatar_ != nullptr, "BulletPeer: null avatar");
  require(options_.h > 0, "BulletPeerOptions::h = ", options_.h, " s, expected > 0");
  const Avatar& a = *avatar_;
  const int N = a.tet.num_nodes(), T = a.tet.num_elements();
  require(N > 0 && T > 0, "BulletPeer: the avatar has no tets");
  require(a.node_weights.rows() == N && a.node_weights.cols() == 24, "BulletPeer: node_weights is ",
          a.node_weights.rows(), " by ", a.node_weights.cols(), ", expected #N = ", N, " by 24");
  require(a.node_role.size() == N, "BulletPeer: node_role has ", a.node_role.size(), " entries, expected #N = ", N);

  // Volumes, lumped masses, per-tet small-strain Lamé parameters.
  volume_.resize(T);
  VecX mass = VecX::Zero(N), mu(T), lambda(T);
  double vol_sim = 0, ratio = 0;  // volume-weighted mean λ/μ over tets with a Simulated node
  for (int t = 0; t < T; ++t) {
    const Vec3 x0 = a.tet.nodes.row(a.tet.elements(t, 0)).transpose();
    Mat3 D;
    for (int c = 1; c < 4; ++c) D.col(c - 1) = a.tet.nodes.row(a.tet.elements(t, c)).transpose() - x0;
    volume_[t] = std::abs(D.determinant()) / 6.0;
    require(volume_[t] > 0, "BulletPeer: tet ", t, " is degenerate (zero volume)");
    const RegionMaterial& m = tet_material(a, t);
    const LameParameters l = isotropic_equivalent(m);
    mu[t] = l.mu;
    lambda[t] = l.lambda;
    bool simulated = false;
    for (int c = 0; c < 4; ++c) {
      mass[a.tet.elements(t, c)] += m.density * volume_[t] / 4.0;
      simulated |= a.node_role[a.tet.elements(t, c)] == int(NodeRole::Simulated);
    }
    if (simulated) vol_sim += volume_[t], ratio += volume_[t] * l.lambda / l.mu;
  }
  require(vol_sim > 0, "BulletPeer: the avatar has no Simulated nodes");
  ratio /= vol_sim;
  // Reference (μ, λ): the largest shear modulus with the mean ratio; tet t scales it by μ_t / μ.
  const LameParameters ref{mu.maxCoeff(), ratio * mu.maxCoeff()};
  scale_ = mu / ref.mu;
  for (int t = 0; t < T; ++t) lambda_mismatch_ = std::max(lambda_mismatch_, std::abs(scale_[t] * ref.lambda - lambda[t]) / lambda[t]);

  for (int n = 0; n < N; ++n)
    if (a.node_role[n] != int(NodeRole::Simulated)) {
      prescribed_.push_back(n);
      mass[n] = 0;  // Bullet: inverse mass 0
    }

  // The world: no contact partners, implicit backward Euler, Bullet's defaults otherwise.
  World& w = *world_;
  w.constraint_solver.setDeformableSolver(&w.solver);
  w.world = std::make_unique<btDeformableMultiBodyDynamicsWorld>(&w.dispatcher, &w.broadphase, &w.constraint_solver,
                                                                 &w.configuration, &w.solver);
  w.world->setGravity(bt(options_.gravity));
  w.world->getWorldInfo().m_gravity = bt(options_.gravity);
  // Implicit backward Euler. Bullet 3.24's implicit solve needs the projection
  // (CG) path: with the default Lagrange-multiplier (CR) path no node moves
  // under gravity (measured: a free tet stays put).
  w.world->setImplicit(true);
  w.world->setUseProjection(true);
  w.world->setLineSearch(options_.line_search);
  if (options_.newton_iterations > 0) w.solver.set_newton_iterations(options_.newton_iterations);

  std::vector<btVector3> x(static_cast<size_t>(N));
  for (int n = 0; n < N; ++n) x[size_t(n)] = bt(a.tet.nodes.row(n).transpose());
  w.body = std::make_unique<btSoftBody>(&w.world->getWorldInfo(), N, x.data(), mass.data());
  btSoftBody& b = *w.body;
  for (int t = 0; t < T; ++t) {
    int e[4] = {a.tet.elements(t, 0), a.tet.elements(t, 1), a.tet.elements(t, 2), a.tet.elements(t, 3)};
    const Vec3 x0 = a.tet.nodes.row(e[0]).transpose();
    const double det = (a.tet.nodes.row(e[1]).transpose() - x0)
                           .dot((a.tet.nodes.row(e[2]).transpose() - x0).cross(a.tet.nodes.row(e[3]).transpose() - x0));
    if (det < 0) std::swap(e[2], e[3]);  // Bullet's element measure is the signed volume
    b.appendTetra(e[0], e[1], e[2], e[3]);
  }
  b.initializeDmInverse();
  b.m_tetraScratches.resize(b.m_tetras.size());
  b.m_tetraScratchesTn.resize(b.m_tetras.size());
  for (int t = 0; t < T; ++t) {
    require(b.m_tetras[t].m_element_measure > 0, "BulletPeer: tet ", t, " has Bullet measure ", b.m_tetras[t].m_element_measure);
    b.m_tetras[t].m_element_measure *= scale_[t];
  }
  b.m_cfg.collisions = 0;  // no contact: nothing else is in the world
  b.m_cfg.drag = 0;
  b.m_sleepingThreshold = 0;
  b.setSelfCollision(false);
  b.setActivationState(DISABLE_DEACTIVATION);
  w.world->addSoftBody(&b);
  const LameParameters bl = neo_hookean_lame(ref);
  w.elastic = std::make_unique<btDeformableNeoHookeanForce>(bl.mu, bl.lambda, 0.0);  // damping 0
  w.world->addForce(&b, w.elastic.get());
  w.gravity = std::make_unique<btDeformableGravityForce>(bt(options_.gravity));
  w.world->addForce(&b, w.gravity.get());
  reset(std::vector<Isometry>(24, Isometry::Identity()));
}

BulletPeer::~BulletPeer() = default;

int BulletPeer::num_nodes() const { return world_->body->m_nodes.size(); }
int BulletPeer::num_tets() const { return world_->body->m_tetras.size(); }
int BulletPeer::num_prescribed() const { return int(prescribed_.size()); }
int BulletPeer::newton_iterations() const { return world_->solver.newton_iterations(); }

VecX BulletPeer::node_masses() const {
  const btSoftBody& b = *world_->body;
  VecX m(b.m_nodes.size());
  for (int n = 0; n < b.m_nodes.size(); ++n) m[n] = b.m_nodes[n].m_im > 0 ? 1.0 / b.m_nodes[n].m_im : 0.0;
  return m;
}

Points BulletPeer::positions() const {
  const btSoftBody& b = *world_->body;
  Points x(b.m_nodes.size(), 3);
  for (int n = 0; n < b.m_nodes.size(); ++n) x.row(n) << b.m_nodes[n].m_x.x(), b.m_nodes[n].m_x.y(), b.m_nodes[n].m_x.z();
  return x;
}

Points BulletPeer::skinned_rest(const std::vector<Isometry>& bones) const {
  require(bones.size() == 24, "BulletPeer: ", bones.size(), " bones, expected 24");
  const Avatar& a = *avatar_;
  Points x(a.tet.num_nodes(), 3);
  for (int n = 0; n < x.rows(); ++n) x.row(n) = skinned_node(a, n, bones).transpose();
  return x;
}

Points BulletPeer::soft_displacement() const {
  const Avatar& a = *avatar_;
  const Points x = positions(), rest = skinned_rest(bones_);
  Points u = Points::Zero(x.rows(), 3);
  for (int n = 0; n < x.rows(); ++n) {
    if (a.node_role[n] != int(NodeRole::Simulated)) continue;
    Mat3 A = Mat3::Zero();
    for (int j = 0; j < 24; ++j)
      if (a.node_weights(n, j) != 0.0) A += a.node_weights(n, j) * bones_[size_t(j)].linear();
    u.row(n) = A.lu().solve((x.row(n) - rest.row(n)).transpose()).transpose();
  }
  return u;
}

double BulletPeer::min_volume_ratio() const {
  const btSoftBody& b = *world_->body;
  double J = std::numeric_limits<double>::infinity();
  for (int t = 0; t < b.m_tetras.size(); ++t) {
    const btSoftBody::Tetra& tet = b.m_tetras[t];
    const btVector3 c1 = tet.m_n[1]->m_x - tet.m_n[0]->m_x, c2 = tet.m_n[2]->m_x - tet.m_n[0]->m_x,
                    c3 = tet.m_n[3]->m_x - tet.m_n[0]->m_x;
    const btMatrix3x3 Ds(c1.x(), c2.x(), c3.x(), c1.y(), c2.y(), c3.y(), c1.z(), c2.z(), c3.z());
    J = std::min(J, double((Ds * tet.m_Dm_inverse).determinant()));
  }
  return J;
}

LameParameters BulletPeer::bullet_lame() const { return {world_->elastic->m_mu, world_->elastic->m_lambda}; }

LameParameters BulletPeer::tet_small_strain_lame(int t) const {
  require(t >= 0 && t < num_tets(), "BulletPeer: tet ", t, " out of range");
  const double s = world_->body->m_tetras[t].m_element_measure / volume_[t];
  const LameParameters b = bullet_lame();
  return {0.75 * b.mu * s, (b.lambda - 0.625 * b.mu) * s};
}

void BulletPeer::reset(const std::vector<Isometry>& bones) {
  const Points x = skinned_rest(bones);
  btSoftBody& b = *world_->body;
  for (int n = 0; n < b.m_nodes.size(); ++n) {
    btSoftBody::Node& node = b.m_nodes[n];
    node.m_x = node.m_q = bt(x.row(n).transpose());
    node.m_v = node.m_vn = btVector3(0, 0, 0);
  }
  bones_ = bones;
  if (options_.rest_follows_skinning) pose_rest_shapes(x);
}

void BulletPeer::pose_rest_shapes(const Points& x) {
  btSoftBody& b = *world_->body;
  for (int t = 0; t < b.m_tetras.size(); ++t) {
    btSoftBody::Tetra& tet = b.m_tetras[t];
    btVector3 c[3];
    for (int k = 0; k < 3; ++k) {
      const int i = int(tet.m_n[k + 1] - &b.m_nodes[0]), i0 = int(tet.m_n[0] - &b.m_nodes[0]);
      c[k] = bt((x.row(i) - x.row(i0)).transpose());
    }
    const btMatrix3x3 Dm(c[0].x(), c[1].x(), c[2].x(), c[0].y(), c[1].y(), c[2].y(), c[0].z(), c[1].z(), c[2].z());
    tet.m_Dm_inverse = Dm.inverse();
    tet.m_element_measure = Dm.determinant() / 6.0 * scale_[t];
  }
}

void BulletPeer::move_prescribed(const std::vector<Isometry>& bones) {
  const Avatar& a = *avatar_;
  btSoftBody& b = *world_->body;
  const double inv_h = 1.0 / options_.h;
  for (int n : prescribed_) {
    const Vec3 s = skinned_node(a, n, bones);
    btSoftBody::Node& node = b.m_nodes[n];
    // The implicit solve starts from m_vn and keeps the velocity of nodes with
    // inverse mass 0 (static constraints): both carry the node onto its target.
    node.m_v = node.m_vn = (bt(s) - node.m_x) * inv_h;
  }
}

double BulletPeer::step(const std::vector<Isometry>& bones_next) {
  require(bones_next.size() == 24, "BulletPeer::step: ", bones_next.size(), " bones, expected 24");
  Timer timer;
  move_prescribed(bones_next);
  if (options_.rest_follows_skinning) pose_rest_shapes(skinned_rest(bones_next));
  world_->world->stepSimulation(options_.h, 0, options_.h);
  bones_ = bones_next;
  return timer.ms();
}

}  // namespace sflsh
