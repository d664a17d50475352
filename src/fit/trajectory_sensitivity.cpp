#include "sflsh/fit/trajectory_sensitivity.hpp"

#include <cmath>
#include <memory>

#include <Eigen/Cholesky>

#include "sflsh/core/error.hpp"
#include "sflsh/core/timer.hpp"
#include "sflsh/sim/avatar_model.hpp"
#include "sflsh/sim/elastic_sensitivity.hpp"
#include "sflsh/sim/energies/elastic.hpp"
#include "sflsh/sim/energies/inertia.hpp"
#include "sflsh/sim/posed_points.hpp"
#include "sflsh/sim/simulator.hpp"

namespace sflsh {
namespace {

/// Σ_i w_i R_i of each point of `points` under `bones`: ∂x_p/∂u (3x3), u the soft displacement.
std::vector<Mat3> skinning_rotations(const PosedPoints& points, const std::vector<Isometry>& bones) {
  std::vector<Mat3> A(points.size());
  for (int p = 0; p < points.size(); ++p) {
    const PosedPoints::Rows r = points.rows(p);
    Mat3 a = Mat3::Zero();
    for (int j = 0; j < r.num_bones; ++j) a += r.bone_weights[j] * bones[r.bones[j]].linear();
    A[p] = a;
  }
  return A;
}

/// U_p S: point p's soft displacement per parameter (3 by #p).
Eigen::Matrix<double, 3, Eigen::Dynamic> soft_rows(const PosedPoints::Rows& r, const MatX& S) {
  Eigen::Matrix<double, 3, Eigen::Dynamic> u = Eigen::Matrix<double, 3, Eigen::Dynamic>::Zero(3, S.cols());
  for (int k = 0; k < r.num_handles; ++k) u += r.handle_weights[k] * S.middleRows<3>(3 * r.handles[k]);
  return u;
}

/// The step's Hessian and gradient at the iterate (bones at t+1, z_t), from the model's own terms.
void assemble(const Model& model, const Avatar& avatar, const Configuration& iterate, const Configuration& q_t,
              const Configuration& q_tm1, VecX& g, MatX& H) {
  const int n = avatar.num_reduced();
  g = VecX::Zero(n);
  H = MatX::Zero(n, n);
  for (const Model::BoundTerm& t : model.terms()) {
    StepContext ctx;
    ctx.avatar = &avatar;
    ctx.layout = t.local_layouts[0];
    ctx.h = model.options().h;
    ctx.gravity = model.options().gravity;
    ctx.q_prev = q_t;
    ctx.q_prev2 = q_tm1;
    ctx.target_bones = iterate.bones;
    ctx.bound.push_back({0, 0, &avatar, ctx.layout, &iterate, &q_t, &q_tm1});
    const auto cache = begin_term_step(*t.term, ctx);
    if (!t.term->active(ctx)) continue;
    VecX gt = VecX::Zero(n);
    MatX Ht = MatX::Zero(n, n);
    t.term->evaluate(ctx, iterate, &gt, &Ht);
    g += gt;
    H += Ht;
  }
}

/// What the sensitivity propagation starts from: the elastic term's parameter
/// derivatives, K (the elastic Hessian at rest: exactly the quadratic part;
/// damping's K₀) and the inertia samples' skinning rotations at t = −h and 0.
struct SensitivityStart {
  std::unique_ptr<ElasticSensitivity> elastic;
  std::vector<int> elastic_index;
  MatX K;
  const InertiaTerm* inertia = nullptr;
  std::vector<Mat3> A_prev, A_cur;
};

SensitivityStart start_sensitivity(const Model& model, const Avatar& av, const FitParameters& params,
                                   const BoneSequence& seq) {
  const int n = av.num_reduced();
  SensitivityStart st;
  st.inertia = model.find_term<InertiaTerm>(0);
  require(st.inertia != nullptr, "simulate_surface: the model has no inertia term");
  const ElasticTerm* elastic = model.find_term<ElasticTerm>(0);
  require(elastic != nullptr, "simulate_surface: the model has no elastic term");
  st.elastic = std::make_unique<ElasticSensitivity>(av, params.elastic(&st.elastic_index), elastic->mean_dilatation());
  StepContext ctx;
  ctx.avatar = &av;
  ctx.layout = model.bodies()[0].layout;
  Configuration rest{seq.bones[0], VecX::Zero(n)};
  VecX g0 = VecX::Zero(n);
  st.K = MatX::Zero(n, n);
  elastic->evaluate(ctx, rest, &g0, &st.K);
  st.A_prev = skinning_rotations(st.inertia->points(), seq.bones_before);
  st.A_cur = skinning_rotations(st.inertia->points(), seq.bones[0]);
  return st;
}

}  // namespace

SurfaceRun simulate_surface(const Avatar& avatar, const FitParameters& params, const VecX& p, double damping,
                            const BoneSequence& seq, const std::vector<int>& steps, const std::vector<int>& vertices,
                            bool jacobian) {
  const int N = seq.num_steps(), n = avatar.num_reduced(), P = params.size();
  require(N >= 0 && seq.bones_before.size() == 24, "simulate_surface: need the bones at t = -h and at least one frame");
  for (size_t i = 0; i < steps.size(); ++i)
    require(steps[i] >= 0 && steps[i] <= N && (i == 0 || steps[i] > steps[i - 1]), "simulate_surface: step ", steps[i],
            " is not increasing in [0, ", N, "]");
  require(p.allFinite(), "simulate_surface: non-finite parameter values");
  auto av = std::make_shared<Avatar>(avatar);
  av->materials = params.materials(avatar.materials, p);
  const double beta = params.damping(p, damping);
  SimulatorOptions so;
  so.h = seq.h;
  so.bones_dynamic = false;
  // The sensitivities below differentiate one Newton step per time step.
  so.newton.nonlinearity_tolerance = 0.0;
  so.damping = beta;
  so.gravity = Vec3(0, seq.gravity_y, 0);
  Simulator sim(avatar_model(av, so));
  const Model& model = sim.model();
  {
    Configuration q0, qm;
    q0.bones = seq.bones[0];
    q0.z = VecX::Zero(n);
    qm.bones = seq.bones_before;
    qm.z = q0.z;
    sim.reset(q0, qm);
  }
  const PosedPoints surface_all = PosedPoints::at_surface(*av);
  const PosedPoints surface = vertices.empty() ? surface_all : surface_all.subset(vertices);
  auto pose_offsets = [&](const std::vector<Isometry>& bones) {
    const Points b = surface_pose_offsets(*av, bones);
    if (vertices.empty() || b.rows() == 0) return b;
    Points s(int(vertices.size()), 3);
    for (size_t i = 0; i < vertices.size(); ++i) s.row(i) = b.row(vertices[i]);
    return s;
  };

  SurfaceRun out;
  // Sensitivity state.
  SensitivityStart start;
  start.inertia = model.find_term<InertiaTerm>(0);
  if (jacobian) {
    Timer timer;
    start = start_sensitivity(model, *av, params, seq);
    out.ms_sensitivity += timer.ms();
  }
  std::unique_ptr<ElasticSensitivity>& es = start.elastic;
  const std::vector<int>& elastic_index = start.elastic_index;
  const MatX& K = start.K;
  const InertiaTerm* inertia = start.inertia;
  std::vector<Mat3>& A_prev = start.A_prev;  // inertia samples' skinning rotations at t − h and t
  std::vector<Mat3>& A_cur = start.A_cur;
  MatX S = MatX::Zero(n, P), S_prev = MatX::Zero(n, P);

  size_t next = 0;
  auto record = [&](int s) {
    if (next >= steps.size() || steps[next] != s) return;
    const Configuration& q = sim.state();
    const Points b = pose_offsets(q.bones);
    out.surface.push_back(surface.world(q, b.rows() ? &b : nullptr));
    if (jacobian) {
      MatX J(3 * surface.size(), P);
      const std::vector<Mat3> A = skinning_rotations(surface, q.bones);
      for (int v = 0; v < surface.size(); ++v) J.middleRows<3>(3 * v) = A[v] * soft_rows(surface.rows(v), S);
      out.jacobian.push_back(std::move(J));
    }
    ++next;
  };
  record(0);
  const double h = seq.h, c = beta / h;
  const VecX& mass = jacobian ? inertia->masses() : VecX();
  for (int s = 0; s < N && next < steps.size(); ++s) {
    const Configuration q_t = sim.state(), q_tm1 = sim.previous_state();
    Timer sim_timer;
    sim.step(seq.bones[s + 1]);
    out.ms_simulate += sim_timer.ms();
    require(sim.state().z.allFinite(), "simulate_surface: the simulation became non-finite at step ", s + 1);
    if (jacobian) {
      Timer timer;
      const VecX delta = sim.state().z - q_t.z;
      Configuration iterate{seq.bones[s + 1], q_t.z};
      VecX g;
      MatX H;
      assemble(model, *av, iterate, q_t, q_tm1, g, H);
      const Eigen::LLT<MatX> llt(H);
      require(llt.info() == Eigen::Success, "simulate_surface: the step's Hessian does not factor at step ", s + 1);
      const VecX newton = -llt.solve(g);
      if ((newton - delta).norm() > 1e-6 * newton.norm() + 1e-12) ++out.shortened_steps;

      MatX A, B, C;
      es->step_derivatives(q_t.z, delta, S, A, B, C);
      MatX R = A * S - C + c * (K * S);
      // Inertia: (1/h²) J₁ᵀ M (2 J₀ S_t − J₋₁ S_{t−1}).
      const std::vector<Mat3> A_next = skinning_rotations(inertia->points(), seq.bones[s + 1]);
      for (int k = 0; k < inertia->points().size(); ++k) {
        const PosedPoints::Rows r = inertia->points().rows(k);
        if (r.num_handles == 0) continue;
        const Eigen::Matrix<double, 3, Eigen::Dynamic> y =
            (mass[k] / (h * h)) * (2.0 * A_cur[k] * soft_rows(r, S) - A_prev[k] * soft_rows(r, S_prev));
        const Eigen::Matrix<double, 3, Eigen::Dynamic> f = A_next[k].transpose() * y;
        for (int j = 0; j < r.num_handles; ++j) R.middleRows<3>(3 * r.handles[j]) += r.handle_weights[j] * f;
      }
      const VecX z_next = sim.state().z;
      for (size_t j = 0; j < elastic_index.size(); ++j)
        R.col(elastic_index[j]) -= es->stiffness_derivative(int(j)) * (z_next + c * delta) + B.col(int(j));
      if (params.damping_index() >= 0) R.col(params.damping_index()) -= K * delta / h;
      S_prev = std::move(S);
      S = llt.solve(R);
      A_prev = std::move(A_cur);
      A_cur = A_next;
      out.ms_sensitivity += timer.ms();
    }
    record(s + 1);
  }
  return out;
}

}  // namespace sflsh
