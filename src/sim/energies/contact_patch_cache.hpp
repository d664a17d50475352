#pragma once
// Private to contact_patch*.cpp: the term's per-step cache and one evaluation
// of Φ and its derivatives (contact_patch.hpp's header comment).
#include <array>
#include <map>
#include <string>
#include <unordered_map>
#include <vector>

#include "sflsh/core/error.hpp"
#include "sflsh/sim/energies/contact_patch.hpp"
#include "sim/energies/contact_patch_cholesky.hpp"

namespace sflsh {

/// Φ and its derivatives at one (q, δu): over the patch DoFs p (3 per patch
/// node, cache order) and the term's local layout q.
struct ContactPatchTerm::Evaluation {
  double energy = 0;
  VecX gp;   // ∂Φ/∂δu
  MatX Hpp;  // its PSD approximation (this evaluation's when has_Hpp: else the storage of an earlier one)
  bool has_Hpp = false;
  VecX gq;   // ∂Φ/∂q
  MatX Hqq;  // Φ_qq: contact (Gauss–Newton), the nodes' inertia less the samples', the bulk share
  MatX Hqp;  // cross block (layout rows by patch DoFs)
  MatX Hzp_stiffening;  // what the dented tets' stiffness adds to Hqp's z rows: Wᵀ (K1 − K0), by patch DoFs
  Vec3 force = Vec3::Zero();           // N, on the body: pressure and friction
  Vec3 friction_force = Vec3::Zero();  // N, its friction part
  Vec3 point_sum = Vec3::Zero();  // Σ |f_s| x_s over the touching samples (world, m·N)
  double point_weight = 0;        // Σ |f_s|
  int active = 0;
  double depth = 0, area = 0;
  VecX anchor_forces;      // 3 per anchor (N, what the tool exerts on the flesh), with the anchors
  double max_stretch = 0;  // m, the largest |x_p − a_p|
};

namespace contact_patch_detail {

/// The 3x3 blocks K_kl = V Σ_{b,c} g_k[b] g_l[c] H_(b,c) of a tet's stiffness
/// (g_k node k's shape gradient, H_(b,c) the 3x3 block of ∂²Ψ/∂vec(F)² that
/// couples F's columns b and c) for a symmetric H: K_lk = K_klᵀ.
using ElementBlocks = std::array<std::array<Mat3, 4>, 4>;
ElementBlocks element_blocks(const Eigen::Matrix<double, 4, 3>& G, double V, const Mat9& H);

struct PatchHistory {
  Vec3 du = Vec3::Zero();       // unposed displacement at t (the fallback start)
  Vec3 du_prev = Vec3::Zero();  // at t − h
  Vec3 d_t = Vec3::Zero();      // world offset A δu at t
  Vec3 d_prev = Vec3::Zero();   // at t − h
  Vec3 du_next = Vec3::Zero();  // fixed by report() for t + h
  Vec3 d_next = Vec3::Zero();
  // The step's start extrapolates δu to t + h, 2 δu(t) − δu(t − h), but starts
  // the other DoFs at q(t) (kinematic bones: at t + h): du_back takes their
  // move over the last step back, Φ_pp⁻¹ Φ_pq (q(t) ⊖ q(t − h)) at that step's
  // last linearization (zero without one); report() fixes du_back_next.
  Vec3 du_back = Vec3::Zero();
  Vec3 du_back_next = Vec3::Zero();
};

/// Doubles per node in PatchCache::saved_state.
inline constexpr size_t kPatchHistoryValues = 16;

struct PatchCache : TermCache {
  /// The patch's displacement and its history are state (δu and its velocity carry over).
  std::unique_ptr<TermCache> clone() const override { return std::make_unique<PatchCache>(*this); }
  /// The history, per node in increasing order: the node, then δu, d_t, δu_next,
  /// d_next and du_back_next (kPatchHistoryValues each): what begin_step reads of it.
  std::vector<double> saved_state() const override;
  void restore_state(const std::vector<double>& values, const std::string& where) override;
  int num_nodes = 0;  // the avatar's tet nodes (a restored node must be one)
  Isometry field_pose = Isometry::Identity();  // world (step frame) pose of the field at t + h (dynamic: at t)
  Isometry shape_in_frame = Isometry::Identity();  // dynamic: this step's shape in the object's body frame
  std::vector<int> faces;                      // candidate skin faces
  std::vector<SkinFaceSample> samples;         // their samples, grouped by face in `faces` order
  std::vector<int> face_first;                 // samples of faces[i]: [face_first[i], face_first[i+1])
  // Friction at time t (contact_patch.hpp, "Friction"), per sample of `samples`:
  // μ λ_s (N; 0: no friction), the normal n_s, and the touched point: where a
  // kinematic object carries it by t + h, a dynamic one's at t (carried by
  // G(q) G_t⁻¹, object_t = G_t); per face, whether a sample has friction.
  std::vector<double> friction_bound;
  std::vector<Vec3> friction_normal, friction_point;
  std::vector<char> face_friction;
  Isometry object_t = Isometry::Identity();
  std::vector<int> vertices;                   // distinct vertices of the candidate faces
  std::unordered_map<int, int> vertex_slot;    // vertex → index into `vertices`
  double radius = 0;                           // this step's patch radius (m, ContactPatchOptions)
  std::vector<int> nodes;                      // patch nodes
  std::unordered_map<int, int> node_slot;      // node → index into `nodes`
  std::vector<int> tets;                       // tets with a patch node
  std::vector<int> prepared_nodes;             // the (sorted) nodes `tets` and what follows were prepared for
  // Per patch tet (`tets` order): its nodes as indices into `tet_nodes`, their
  // patch slots (−1: not a patch node), and the material's small-strain Hessian.
  std::vector<int> tet_nodes;                  // distinct nodes of the patch tets
  std::vector<std::array<int, 4>> tet_local, tet_slot;
  // The (tet node, patch slot) pairs that share a patch tet, per tet node in
  // increasing slot order ([cross_first[i], cross_first[i+1]) into cross_slot),
  // and per patch tet the pair of each of its (k, l) node pairs (−1: l not a patch node).
  std::vector<int> cross_first, cross_slot;
  std::vector<std::array<int, 16>> tet_cross;
  // Per (tet node, patch slot) pair: Σ over the patch tets of the subspace
  // share's stiffness block K0 (constant for a set of tets).
  std::vector<Mat3> node_cross;
  // K0_pp: the subspace share's stiffness over the patch DoFs (the guard's, compute).
  MatX K0pp;
  // add_patch_elasticity's accumulators, kept for their storage.
  std::vector<Vec3> scratch_node_grad;
  std::vector<Mat3> scratch_node_stiffening;
  std::vector<Mat9> tet_H2;
  // Per patch tet, the subspace's quadratic share (constant): its Hessian per
  // unit volume and its stiffness blocks over the tet's node pairs.
  std::vector<Mat9> tet_Hq;
  std::vector<ElementBlocks> tet_K0;
  // The bulk share mean dilatation leaves out of Φ_zz (contact_patch_evaluation.cpp,
  // elasticity) over the handles the patch tets touch: constant for a set of tets.
  std::vector<int> bulk_handles;
  MatX bulk_hessian;
  std::vector<int> bulk_tets;  // the tets it was computed for
  std::vector<Vec3> x_star, d_pred;            // per patch node: subspace prediction, offset prediction
  // The q blocks (Φ_qq, Φ_qp, the stiffening: nq by nq and nq by 3P, a few
  // hundred kB, mostly zero) hold nonzeros only in the rows of the DoFs the
  // patch's points and tets depend on: `q_rows` this step (increasing), and
  // `q_rows_written` every row any evaluation into this cache's storage has
  // written since it was allocated. An evaluation zeroes the latter, the
  // condensation reads the former.
  std::vector<int> q_rows, q_rows_written;
  std::vector<char> q_row_written;             // per row of the system: in q_rows_written
  std::vector<int> samples_in_patch;           // inertia cubature samples whose main node is a patch node
  std::vector<Vec3> sample_x_star;             // their predictions
  bool releasing = false;                      // no contact: δu prescribed (decaying), not minimized
  VecX du;                                     // last minimizer (3 per patch node)
  VecX du_predicted;                           // the step's first start: 2 δu(t) − δu(t − h) + du_back
  bool settled = false;                        // every patch node was in the last step's patch
  int inner_iterations = 0, minimizations = 0; // this step's Newton iterations on δu, and minimizations
  // The configuration `du` minimizes Φ at (skipped when asked again), and the
  // linearization of the last Hessian evaluation (at the body's q_lin and a
  // dynamic object's object_lin): δu(q) ≈ du_lin − Φ_pp⁻¹ Φ_pq (q ⊖ q_lin).
  bool solved = false;
  Configuration q_solved;
  Isometry object_solved = Isometry::Identity();
  bool linearized = false;
  Configuration q_lin, object_lin;
  VecX du_lin;
  // Φ_pq = Hqpᵀ + the dented tets' stiffening of its z columns (z_lin: their offset).
  MatX Hqp, Hzp_stiffening;
  int z_lin = 0;
  PatchPattern pattern;  // the pattern and ordering of every factor below (one analysis per patch size)
  PatchCholesky Hpp_llt;
  PatchCholesky start_llt;  // Φ_pp's factor at a Newton iteration's start (minimize_patch)
  /// Φ_pp⁻¹ Φ_pq dq at the last linearization (dq over the term's layout).
  VecX linear_response(const VecX& dq) const {
    VecX b = VecX::Zero(Hqp.cols());
    for (int r : q_rows) {
      if (dq[r] == 0) continue;
      b.noalias() += dq[r] * Hqp.row(r).transpose();
      if (r >= z_lin && r < z_lin + Hzp_stiffening.rows()) b.noalias() += dq[r] * Hzp_stiffening.row(r - z_lin).transpose();
    }
    return Hpp_llt.solve(b);
  }
  // Evaluations kept for their storage (evaluate_patch resets them in place):
  // a Newton iteration's start, and the inner Newton iteration's point and trial.
  ContactPatchTerm::Evaluation start, inner, inner_trial;
  PatchCholesky below_llt, guarded_llt;  // the complement's guard (compute)
  // The complement's scratch (compute): the rows of Φ_pq it reads, X = L⁻¹ P Φ_pq
  // and XᵀX (kept: at a few hundred kB fresh pages cost more than the products).
  std::vector<char> schur_row;
  MatX schur_C, schur_S;
  MatXr schur_X;
  PatchCholesky inner_llt;               // the inner Newton iteration's Φ_pp (minimize_patch)
  // The step's last trial: its configuration, δu and evaluation.
  bool has_trial = false;
  Configuration trial_q;
  Isometry trial_object = Isometry::Identity();
  VecX trial_du;
  ContactPatchTerm::Evaluation trial;
  std::map<int, PatchHistory> history;  // ordered: the patch's slots and a checkpoint do not depend on hashing
  // The step's anchors (PatchAnchors), by increasing vertex: the tool point at
  // t + h and at t, and the vertex (with its patch offset) at t; step frame.
  std::vector<int> anchor_vertices;
  std::vector<Vec3> anchor_target, anchor_a_t, anchor_x_t;
};

inline PatchCache& patch_cache(const StepContext& ctx, const std::string& name) {
  require(ctx.cache != nullptr, name, ": no cache (call begin_step through begin_term_step or the integrator)");
  return static_cast<PatchCache&>(*ctx.cache);
}

inline const DofLayout& local_layout(const StepContext& ctx) {
  return ctx.bound.empty() ? ctx.layout : ctx.bound[0].layout;
}

/// A skin vertex at q with the patch's displacement: x = x_v(q) + A offset,
/// offset = Σ_c b_c δu_c over its tet's nodes (unposed), A = Σ_j w_j R_j.
struct PatchedVertex {
  Vec3 x = Vec3::Zero();
  Mat3 A = Mat3::Identity();
  Vec3 offset = Vec3::Zero();
  std::array<std::pair<int, double>, 4> couple;  // (patch slot or −1, barycentric weight) per tet node
};

/// The subspace's displacement W_n z (unposed) at each node of the patch's
/// tets (`c.tet_nodes` order); zero at nodes that are not Simulated.
std::vector<Vec3> tet_node_subspace_displacements(const Avatar& a, const PatchCache& c, const VecX& z);

/// Vertex `v` of `vertices` (the term's skin points) at q with δu (slots of `c`).
PatchedVertex patched_vertex(const Avatar& a, const PosedPoints& vertices, const PatchCache& c, int v,
                             const Configuration& q, const VecX& du);

/// Adds the generalized force of a world force `f` on an offset d = Σ_j w_j R_j o
/// (o unposed) to the bones' rotations: ∂d/∂ω_j = −[w_j R_j o]×, so bone j's
/// ω gains (w_j R_j o) × f (translations do not move an offset).
template <class Row>
void add_offset_rotation_gradient(const Row& w, const std::vector<Isometry>& bones, const Vec3& o, const Vec3& f,
                                  const DofLayout& L, VecX& gq) {
  if (!L.bones_dynamic) return;
  for (int j = 0; j < w.size(); ++j)
    if (w[j] != 0.0) gq.segment<3>(L.bone_offset(j)) += (w[j] * (bones[j].linear() * o)).cross(f);
}

}  // namespace contact_patch_detail
}  // namespace sflsh
