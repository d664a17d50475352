#pragma once
// The immutable half of the runtime (MuJoCo's mjModel role): the bodies of a
// scene, the DoF blocks they contribute, the energy terms bound to them and
// the solver settings. Built once by a ModelBuilder and shared (const) by any
// number of States, threads and runs; a step is a function of
// (Model, State, StepInputs) (sim/step.hpp).
//
// Block DoF layout of the step vector δ (sizes in DoFs):
//   [ body 0: bone 0 (6) … bone 23 (6) | soft (3K) ][ body 1: … ] …
// (a dynamic rigid object is a body with one 6-DoF block).
// A body with kinematic (prescribed) bones contributes no bone blocks; a body
// without handles no soft block. Each body's blocks are contiguous, so a term
// on one body writes straight into the global system; a term coupling bodies
// gets a local system (its blocks, concatenated) that the assembler scatters.
//
// Groups. Bodies that no term couples are independent: the model splits them
// into groups (connected components of the body–term graph), orders the step
// vector group by group, and each step solves every group on its own (its own
// Newton system, centred on its own first pelvis; in parallel when
// ModelOptions::parallel_groups). A dense solve then costs Σ n_g³ instead of
// (Σ n_g)³, and two avatars that do not interact get exactly their
// single-avatar results.
#include <memory>
#include <string>
#include <vector>

#include "sflsh/asset/avatar.hpp"
#include "sflsh/sim/configuration.hpp"
#include "sflsh/sim/energy_term.hpp"
#include "sflsh/sim/input_ids.hpp"
#include "sflsh/sim/newton_step.hpp"

namespace sflsh {

/// One block of the step vector.
struct DofBlock {
  enum class Kind { Bone, Soft };
  Kind kind = Kind::Soft;
  int body = 0;    ///< owning body
  int bone = -1;   ///< bone index (Kind::Bone), else −1
  int offset = 0;  ///< first DoF in the global step vector
  int size = 0;    ///< 6 (bone) or 3K (soft)
};

/// A body as the scene declares it: an avatar, or (avatar null) a dynamic
/// rigid object — one "bone" G mapping the object's frame, centred on its
/// centre of mass, to the world; 6 DoFs turning about the centre of mass, no
/// soft block. Its mass enters through the terms the scene adds
/// (rigid_body_terms.hpp); kinematic and static objects are not bodies but
/// world frames of the step inputs (ModelBuilder::add_frame, StepInputs::frames).
struct BodySpec {
  std::string name;                        ///< unique within the model (e.g. "avatar", "alice", "ball")
  std::shared_ptr<const Avatar> avatar;    ///< its asset (shared, immutable); null: a rigid object
  bool bones_dynamic = false;              ///< bones are DoFs (true) or prescribed by the targets (false);
                                           ///< a rigid object is always dynamic
};

/// Solver settings of a model.
struct ModelOptions {
  double h = 1.0 / 60.0;             ///< time step (s)
  Vec3 gravity = Vec3(0, -9.81, 0);  ///< m/s², world, Y up
  NewtonOptions newton;              ///< iterations, line search, step caps (newton_step.hpp)
  /// Step independent groups concurrently (TBB). Results do not depend on it.
  bool parallel_groups = true;
};

class Model {
 public:
  struct Body {
    std::string name;
    std::shared_ptr<const Avatar> avatar;  ///< null for a rigid object
    bool bones_dynamic = false;
    DofLayout layout;  ///< its blocks in the global step vector (base = its first DoF)
    bool rigid() const { return avatar == nullptr; }
    /// Bones of its configuration: 24 for an avatar, 1 for a rigid object.
    int num_bones() const { return layout.num_bones; }
  };
  /// A term and where its local system sits in the global one.
  struct BoundTerm {
    std::shared_ptr<const EnergyTerm> term;
    std::vector<int> bodies;                 ///< bound bodies (≥ 1)
    std::vector<DofLayout> local_layouts;    ///< per bound body, in the term's local system
    TermPlacement placement;                 ///< where the local system sits in the global one
    std::vector<FrameId> frames;             ///< its input frames (EnergyTerm::input_frames order)
    AnchorSetId anchor_set;                  ///< its anchored points (invalid: it reads none)
  };

  /// Bodies coupled by terms, solved together (see header comment). Layouts
  /// and placements here are relative to the group's first DoF.
  struct Group {
    std::vector<int> bodies;               ///< model body indices, increasing
    std::vector<int> terms;                ///< model term indices, in model order
    int offset = 0, size = 0;              ///< the group's interval of the global step vector
    std::vector<DofLayout> layouts;        ///< per group body
    std::vector<TermPlacement> placements; ///< per group term
    std::vector<std::vector<int>> slots;   ///< per group term: each bound body's index in `bodies`
  };

  const std::vector<Body>& bodies() const { return bodies_; }
  const std::vector<Group>& groups() const { return groups_; }
  const std::vector<BoundTerm>& terms() const { return terms_; }
  const std::vector<DofBlock>& blocks() const { return blocks_; }
  const ModelOptions& options() const { return options_; }
  /// Size of the step vector δ (all blocks).
  int num_dofs() const { return num_dofs_; }
  /// Index of the body called `name`; throws naming the known bodies.
  int body_index(const std::string& name) const;
  /// Names of the step inputs' world frames, by FrameId::index.
  const std::vector<std::string>& frame_names() const { return frame_names_; }
  /// The world frame called `name`; throws naming the known frames.
  FrameId frame_id(const std::string& name) const;
  /// The world frame called `name`, or an invalid id.
  FrameId find_frame(const std::string& name) const;
  /// Names of the anchor sets, by AnchorSetId::index.
  const std::vector<std::string>& anchor_set_names() const { return anchor_set_names_; }
  /// The anchor set called `name`; throws naming the known sets.
  AnchorSetId anchor_set_id(const std::string& name) const;
  /// The first term of type T bound to `body` (e.g. the ElasticTerm for
  /// diagnostics), or null.
  template <class T>
  const T* find_term(int body) const {
    for (const BoundTerm& t : terms_)
      if (t.bodies[0] == body)
        if (const T* p = dynamic_cast<const T*>(t.term.get())) return p;
    return nullptr;
  }
  /// One line per block and per term: which blocks each term touches.
  std::string describe() const;

 private:
  friend class ModelBuilder;
  std::vector<Body> bodies_;
  std::vector<BoundTerm> terms_;
  std::vector<Group> groups_;
  std::vector<DofBlock> blocks_;
  std::vector<std::string> frame_names_, anchor_set_names_;
  ModelOptions options_;
  int num_dofs_ = 0;
};

/// Assembles a Model: bodies first, then the terms that act on them.
class ModelBuilder {
 public:
  ModelBuilder() = default;
  explicit ModelBuilder(ModelOptions options) : options_(std::move(options)) {}
  /// Adds a body; returns its index. Its bones turn about its own joints
  /// (DofLayout::bone_pivots = avatar.joints_rest when it has 24 joints); a
  /// rigid object turns about its centre of mass (its frame's origin).
  int add_body(BodySpec spec);
  /// Binds `term` to `bodies` (indices from add_body; the first is the one its
  /// single-body fields describe). The term declares which blocks of each it
  /// touches. Returns its index in the model (Model::terms()).
  int add_term(std::shared_ptr<const EnergyTerm> term, std::vector<int> bodies);
  /// Convenience: a term on one body.
  int add_term(EnergyTermPtr term, int body) {
    return add_term(std::shared_ptr<const EnergyTerm>(std::move(term)), {body});
  }
  /// The world frame called `name` of the step inputs (StepInputs::frames):
  /// a new id, or the frame's id when it is already registered. add_term
  /// registers the frames its term reads (EnergyTerm::input_frames).
  FrameId add_frame(const std::string& name);
  /// The anchor set called `name` (StepInputs::anchors), new or already
  /// registered; add_term registers its term's (EnergyTerm::input_anchor_set).
  AnchorSetId add_anchor_set(const std::string& name);
  ModelOptions& options() { return options_; }
  const Avatar& avatar(int body) const;
  int num_bodies() const { return int(specs_.size()); }
  /// The model (validates: names unique, options finite and positive).
  std::shared_ptr<const Model> build() const;

 private:
  ModelOptions options_;
  std::vector<BodySpec> specs_;
  std::vector<std::pair<std::shared_ptr<const EnergyTerm>, std::vector<int>>> terms_;
  std::vector<std::vector<FrameId>> term_frames_;  ///< per term: its input frames
  std::vector<AnchorSetId> term_anchor_sets_;      ///< per term: its anchor set
  std::vector<std::string> frame_names_, anchor_set_names_;
};

}  // namespace sflsh
