#pragma once
// A scene file (`sflsh simulate scene.yaml`): bodies (avatars),
// rigid objects, contact, solver and outputs, as plain data. Nothing here
// builds simulation objects; the runtime turns a SceneDescription into its
// model and state.
//
// Top-level keys follow DESIGN.md §5b (bodies, objects, tools, contact,
// solver, output; a tool's pose comes from keyframes, a pose file or a live
// UDP stream; tools touch every body, whatever `pairs` says).
// Coordinates are the avatar's frame, Y up, facing +Z: the built-in avatar stands on y = 0 (soles at y = -0.01 m, pelvis
// at 0.94 m, belly front near z = 0.11 m at y = 1.05 m).
//
// Example (every key shown; defaults in the comments, "required" where there is none):
//
//   solver:
//     dt: 1/60                  # s, "N/D" or a number in (0, 0.1]; default 1/60
//     seconds: 3                # simulated time (s, >= 0); default 0 = the longest body
//                               # motion (then some body needs a motion)
//     newton_iters: 1           # Newton iterations per step, 1..100; default 1
//     iterations_after_damping: 3  # more iterations while the last one is damped by a cap, 0..100; default 3
//     line_search: false        # backtracking line search; default false
//     nonlinearity_tolerance: auto # one more Newton iteration where a full step's energy change
//                               # is off its quadratic model by more than this share (|rho - 1|),
//                               # >= 0 (0 = off); default auto: 0.05 when every body's bones are
//                               # prescribed and no dynamic rigid object or tool, else off
//     gravity: [0, -9.81, 0]    # m/s^2, world, Y up; default [0, -9.81, 0]
//     damping: 0                # stiffness-proportional soft-tissue damping (s, >= 0); default 0
//   output:                     # paths relative to the working folder (like the CLI flags)
//     out: result.h5            # result file; default result.h5
//     export: result.glb        # optional: .pc2, .glb, or frames_%04d.obj/.ply/.glb
//     render: result.png        # optional: PNG strip
//     render_frames: 6          # frames in the strip (>= 1); default 6
//     fps: 30                   # output frames per simulated second (> 0); default 30
//   contact:
//     stiffness:                # penalty ½k·d² per contact sample (N/m, >= 0)
//       body_object: 2.0e5      # skin samples against rigid objects; default 2e5
//                               # (an avatar dropped 0.4 m onto the floor: 8.9 mm deepest)
//       body_body: 1.0e6        # bone capsules of different bodies; default 1e6
//       self: 1.0e5             # non-adjacent capsules of one body; default 1e5
//     friction: 0.5             # Coulomb μ between skin and rigid objects (>= 0); default 0.5
//     self_contact: false       # default false
//     sample_spacing: 0         # m between skin samples (>= 0); default 0 = every skin vertex
//     patch:                    # contact that dents (rigid objects, tools): a
//                               # pressure over the skin's faces with `friction`, and a full-space
//                               # patch under it (sim/energies/contact_patch.hpp), also under
//                               # tools' grasp anchors; `patch: true` takes the defaults;
//                               # default off
//       radius: 0.04            # m: nodes within it of the near skin; grows to 1.5 contact radii
//       max_nodes: 120          # nodes in one patch at most (>= 1)
//       pressure_stiffness: 1.0e8   # N/m³ (> 0)
//       spacing: 0.002          # m between face samples (> 0)
//     bodies:                   # body-body contact
//       model: skin             # skin (the skins press, the flesh gives; capsule cores behind)
//                               # or capsules (rigid bone capsules alone); default skin
//       pressure_stiffness: 1.0e8   # N/m³ (> 0)
//       spacing: 0.01           # m between face samples (> 0)
//       core_radius: 0.5        # share of each capsule's radius kept as a core, (0, 1]
//     pairs: all                # default all: every body-object and body-body pair;
//                               # or a list of name pairs: [[alice, floor], [alice, bob]]
//   bodies:                     # required, at least one
//     - name: alice             # required; names are unique across bodies and objects
//       avatar: default         # required: `default` (the built-in body, precomputed on
//                               # first use and cached: minutes once, then instant), or an
//                               # avatar file relative to this file's folder
//                               # (make one with `sflsh precompute --out avatar.h5`)
//       betas: [1.5, -1]        # avatar: default only: its shape (up to 10 numbers); default 0
//       motion: builtin:walk    # none | builtin:NAME | a motion file (relative to this
//                               # file's folder: .npz, .bvh, .fbx, ...); default none
//       placement:              # where the motion is played in the world
//         offset: [0, 0, 0]     # m; default [0, 0, 0]
//         heading_deg: 90       # rotation about +Y, degrees; default 0
//       bones: dynamic          # dynamic | kinematic; default dynamic
//       material: soft.yaml     # optional material file (relative to this file's folder)
//       velocity: [0, 0, 0]     # m/s, initial linear velocity; with a motion the placement
//                               # also travels at it (a walk in place walks along it); default 0
//   objects:                    # optional
//     - name: floor             # required
//       shape: {type: plane, normal: [0, 1, 0]}   # required; see below
//       kind: static            # static | kinematic | dynamic; default static
//       position: [0, 0, 0]     # m (static, dynamic); default [0, 0, 0]
//       orientation: [1, 0, 0, 0]  # unit quaternion w, x, y, z (static, dynamic); default identity
//     - name: ball
//       shape: {type: sphere, radius: 0.11}
//       kind: dynamic
//       density: 80             # kg/m^3 (> 0), or mass: 0.45 (kg, > 0); exactly one
//       position: [0, 1.1, 0.6]
//       velocity: [0, 0, -4]    # m/s; default [0, 0, 0]
//       angular_velocity: [0, 0, 0]  # rad/s, world; default [0, 0, 0]
//     - name: press
//       shape: {type: box, size: [0.3, 0.05, 0.3]}
//       kind: kinematic         # pose from keyframes (linear position, slerped rotation)
//       keyframes:              # required, times >= 0 strictly increasing
//         - {time: 0, position: [0, 1.3, 0.3], orientation: [1, 0, 0, 0]}
//         - {time: 2, position: [0, 1.1, 0.3]}   # orientation defaults to identity
//   tools:                      # optional: teleoperated tools (scene_session.hpp)
//     - name: pincher           # required; unique across bodies, objects and tools
//       shape: {type: capsule, radius: 0.005, length: 0.03}  # optional contact shape (as objects')
//       keyframes:              # the pose source: keyframes, or `pose_file` (exactly one)
//         - {time: 0, position: [0, 1.1, 0.12], orientation: [1, 0, 0, 0], closure: 1.0}
//         - {time: 0.2, position: [0, 1.1, 0.12], closure: 0}   # closure: jaw opening, rad
//       pose_file: pinch.csv    # CSV (time,x,y,z,qw,qx,qy,qz,closure) or JSON lines (README)
//       pose_interpolation: linear   # or hold: a recorded live session (sflsh run --record)
//       pose_stream: {port: 7001, max_speed: 20}  # or a live device (UDP, README); keyframes
//                               # then give the pose until the first sample
//       coupling: {stiffness: 2.0e4, damping: auto, rotational_stiffness: 20,
//                  rotational_damping: auto, mass: 0.1, max_force: 20, haptic_gain: 1}
//                               # optional: a dynamic tool pulled by its device (virtual coupling)
//       gripper:                # optional: jaws that turn about a hinge by ±closure/2 (tool frame)
//         hinge: {origin: [0, 0.03, 0], axis: [1, 0, 0]}
//         jaws:
//           - {shape: {type: capsule, radius: 0.003, length: 0.02}, offset: [0, 0.01, 0.004], side: 1}
//           - {shape: {type: capsule, radius: 0.003, length: 0.02}, offset: [0, 0.01, -0.004], side: -1}
//       grasp:                  # optional: proximity sensors and anchors (AMBF Alg. 3)
//         sensors: [{origin: [0, 0, 0], direction: [0, 0, -1], range: 0.01}]  # tool frame, m
//         closure_threshold: 0.2   # rad: anchors while the closure is below it; default 0.2
//         hardness: 2.0e4          # N/m per anchor; default 2e4
//         damping: 1.0             # N·s/m per anchor; default 1
//
// Shapes (local frame; axes of symmetry along local +Y; lengths in m, > 0):
//   plane    {normal: [0, 1, 0]}               half-space below the plane through the
//                                               object's position (a plane cannot be dynamic)
//   sphere   {radius}
//   box      {size: [x, y, z]}                  full edge lengths
//   capsule  {radius, length}                   length: between the cap centres (>= 0)
//   cylinder {radius, length}                   capped, full height
//   mesh     {file, scale: 1, voxel_size: 0.005, padding: 0.02, band: 0}
//            a closed triangle mesh (OBJ/STL/PLY/... through assimp; relative to this
//            file's folder) times `scale`, baked into a grid SDF (mesh/mesh_sdf_bake.hpp)
//
// Errors are one line "FILE:LINE: KEY.PATH: what was expected", e.g.
//   scene.yaml:14: objects[2].shape.radius: must be > 0, got -0.1
// for malformed YAML, unknown keys, missing required keys, wrong types,
// non-finite numbers, out-of-range values (negative mass, radius, density,
// ...), duplicate names, pairs naming an unknown body/object, and avatar,
// motion, material or mesh files that do not exist. Whether a mesh is closed
// is checked when it is baked (prepare_scene_assets, before a session is built).
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "sflsh/core/types.hpp"
#include "sflsh/geometry/sdf.hpp"
#include "sflsh/sim/energies/contact_patch.hpp"
#include "sflsh/sim/energies/skin_contact.hpp"
#include "sflsh/sim/newton_step.hpp"

namespace sflsh {

/// One avatar in the scene.
/// `avatar: default`: the built-in body, precomputed on first use and cached
/// (precompute/cached_avatar.hpp; the sflsh commands resolve it), at shape `betas`.
constexpr const char* kDefaultAvatar = "default";
constexpr long kMaxDefaultAvatarBetas = 10;  ///< the built-in body's shape directions

struct BodyDescription {
  std::string name;
  /// Avatar file (absolute after reading), or kDefaultAvatar until it is
  /// resolved to the cached avatar's path.
  std::string avatar;
  bool default_avatar = false;     ///< avatar: default (the built-in body)
  VecX betas;                      ///< avatar: default's shape (empty: β = 0)
  std::string motion = "none";     ///< "none", "builtin:NAME" or a file (absolute after reading)
  Vec3 offset = Vec3::Zero();      ///< placement: m, world offset
  double heading_deg = 0;          ///< placement: rotation about +Y, degrees
  bool bones_dynamic = true;       ///< bones: dynamic (true) | kinematic
  std::string material;            ///< material override file (absolute), "" = none
  Vec3 velocity = Vec3::Zero();    ///< m/s, initial linear velocity (with a motion: the placement's too)
};

enum class ShapeType { Plane, Sphere, Box, Capsule, Cylinder, Mesh };
/// "plane", "sphere", "box", "capsule", "cylinder", "mesh".
const char* shape_type_name(ShapeType type);

/// A rigid object's shape in its local frame (only the fields of its type are used).
struct ShapeDescription {
  ShapeType type = ShapeType::Sphere;
  Vec3 normal = Vec3::UnitY();         ///< plane: outward normal (unit)
  double radius = 0;                   ///< sphere, capsule, cylinder (m)
  Vec3 size = Vec3::Zero();            ///< box: full edge lengths (m)
  double length = 0;                   ///< capsule: between cap centres; cylinder: height (m)
  std::string mesh_file;               ///< mesh: file (absolute after reading)
  double mesh_scale = 1;               ///< mesh: coordinate factor (0.001 for mm files)
  double voxel_size = 0.005;           ///< mesh: grid SDF spacing (m)
  double padding = 0.02;               ///< mesh: grid room around the mesh (m)
  double band = 0;                     ///< mesh: exact band (m), 0 = full grid
  /// mesh: its grid SDF, baked (or loaded from the cache) by prepare_scene_assets
  /// (sflsh/scene_assets/scene_assets.hpp) before the scene is built: the
  /// runtime reads the grid and never bakes (baking takes CGAL). Not written back.
  std::shared_ptr<const geometry::Sdf> baked_sdf;
  std::string bake_report;             ///< what the bake or the cache did (one line)
  /// Where the shape was read ("scene.yaml:12: objects[2].shape"), for later
  /// errors (baking); not written back.
  std::string location;
};

enum class ObjectKind { Static, Kinematic, Dynamic };
/// "static", "kinematic", "dynamic".
const char* object_kind_name(ObjectKind kind);

/// A pose of a kinematic object at a time.
struct Keyframe {
  double time = 0;                                         ///< s
  Vec3 position = Vec3::Zero();                            ///< m, world
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();  ///< unit, local to world
};

struct RigidObjectDescription {
  std::string name;
  ShapeDescription shape;
  ObjectKind kind = ObjectKind::Static;
  /// Static and dynamic: the (initial) pose. Kinematic: the first keyframe's.
  Vec3 position = Vec3::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
  std::vector<Keyframe> keyframes;       ///< kinematic only, times strictly increasing
  double density = 0;                    ///< dynamic: kg/m³, or 0 when `mass` is given
  double mass = 0;                       ///< dynamic: kg, or 0 when `density` is given
  Vec3 velocity = Vec3::Zero();          ///< dynamic: m/s
  Vec3 angular_velocity = Vec3::Zero();  ///< dynamic: rad/s, world axes
};

/// A pose of a tool at a time: keyframe of its pose source.
struct ToolKeyframe {
  double time = 0;                                                  ///< s
  Vec3 position = Vec3::Zero();                                     ///< m, world
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();  ///< unit, tool to world
  double closure = 0;  ///< gripper jaw opening (rad, 0 = shut; teleop/pose_sample.hpp)
};

/// A proximity sensor on a tool: a ray in the tool's frame (AMBF Fig. 5).
struct ToolSensorDescription {
  Vec3 origin = Vec3::Zero();     ///< m, tool frame
  Vec3 direction = -Vec3::UnitY();  ///< unit, tool frame
  double range = 0.01;            ///< m
};

/// One jaw of a tool's gripper: a contact shape in its own frame, placed in
/// the tool frame at `offset` and turned about the gripper's hinge by
/// side · closure / 2 (side +1 or −1: the two jaws open in opposite senses).
struct ToolJawDescription {
  ShapeDescription shape;
  Vec3 offset = Vec3::Zero();  ///< m, the jaw frame's origin in the tool frame at closure 0
  double side = 1;             ///< +1 or −1
};

/// Virtual coupling of a tool to its device (sim/energies/virtual_coupling.hpp).
struct ToolCouplingDescription {
  double stiffness = 2.0e4;             ///< N/m
  double damping = -1;                  ///< N·s/m; < 0: critical, 2√(k m)
  double rotational_stiffness = 20.0;   ///< N·m/rad
  double rotational_damping = -1;       ///< N·m·s/rad; < 0: critical, 2√(k_r I)
  double mass = 0.1;                    ///< kg, the tool body (gravity-compensated by the device)
  double max_force = 20.0;              ///< N: the force sent to the device is clamped to it
  double haptic_gain = 1.0;             ///< the force and torque sent to the device are scaled by it
};

/// A teleoperated tool: a frame driven by its pose source —
/// kinematic, or with `coupling` a dynamic body pulled by its device —,
/// optionally with a contact shape and a grasp (sensors + anchors).
struct ToolDescription {
  std::string name;
  bool has_shape = false;
  ShapeDescription shape;                  ///< contact shape (when has_shape)
  std::vector<ToolKeyframe> keyframes;     ///< pose source: keyframes ...
  std::string pose_file;                   ///< ... or a pose file (CSV / JSON lines), absolute
  bool pose_file_hold = false;             ///< pose file read with zero-order hold (a recording), not linearly
  /// ... or a live UDP stream on 127.0.0.1:stream_port (0: any free port;
  /// −1: none); keyframes, if given, hold the tool until the first sample.
  int stream_port = -1;
  double stream_max_speed = 20.0;          ///< m/s: samples implying a faster jump are rejected
  /// s: a live device takes over a tool that has a pose (keyframes, pose file)
  /// by fading out their offset over this time (teleop/pose_ramp.hpp); 0: at once.
  double stream_ramp_in = 0.5;
  bool coupled = false;                    ///< virtual coupling (else kinematic)
  ToolCouplingDescription coupling;
  /// Two-jaw gripper (optional): the hinge (a point and an axis in the tool
  /// frame) and the jaws, which turn about it with the device's closure.
  Vec3 hinge_origin = Vec3::Zero();
  Vec3 hinge_axis = Vec3::UnitX();
  std::vector<ToolJawDescription> jaws;
  std::vector<ToolSensorDescription> sensors;  ///< grasp sensors; none: the tool cannot grasp
  double closure_threshold = 0.2;          ///< rad: grasp while the closure is below it
  double hardness = 2.0e4;                 ///< N/m per anchor
  double damping = 1.0;                    ///< N·s/m per anchor
};

struct ContactDescription {
  double body_object_stiffness = 2.0e5;  ///< N/m per skin sample
  double body_body_stiffness = 1.0e6;    ///< N/m per capsule pair
  double self_stiffness = 1.0e5;         ///< N/m per capsule pair of one body
  double friction = 0.5;                 ///< Coulomb μ, skin against rigid objects
  bool self_contact = false;
  double sample_spacing = 0;             ///< m; 0 = every skin vertex
  /// true: every body–object and body–body pair collides; false: only `pairs`.
  bool all_pairs = true;
  /// Colliding pairs by name (each has a body; object–object contact is not modelled).
  std::vector<std::pair<std::string, std::string>> pairs;
  /// contact.patch: body–object contact sampled over the skin's faces with a
  /// pressure stiffness, and a full-space patch under it
  /// (sim/energies/contact_patch.hpp), for static, kinematic and dynamic
  /// objects (a dynamic one's 6 DoFs join the condensed system), with
  /// `friction` lagged per step over the face samples. Tools (and their
  /// jaws), kinematic or coupled, get it too, their grasp anchors in the patch
  /// of the tool's shape (or a patch of their own: PatchAnchors).
  bool patch = false;
  double patch_radius = ContactPatchOptions().patch_radius;  ///< m
  int max_patch_nodes = ContactPatchOptions().max_patch_nodes;
  double pressure_stiffness = kDefaultPressureStiffness;      ///< N/m³
  double patch_spacing = kDefaultContactSpacing;              ///< m, face sample spacing
  /// contact.bodies: how two bodies meet. Skin (default): skin against skin
  /// with a pressure stiffness, the flesh of both giving
  /// (sim/energies/skin_contact.hpp), and the bone capsules shrunk to cores
  /// (`core_radius` of their radius) as a backstop; Capsules: bone capsules
  /// alone (rigid, body_body_stiffness per pair).
  enum class BodyModel { Skin, Capsules };
  BodyModel body_model = BodyModel::Skin;
  double body_pressure_stiffness = SkinContactOptions().pressure_stiffness;  ///< N/m³
  double body_spacing = SkinContactOptions().spacing;                        ///< m
  double core_radius = 0.5;  ///< share of each capsule's radius kept as its core (0, 1]
};

struct SolverDescription {
  double dt = 1.0 / 60.0;               ///< s
  double seconds = 0;                   ///< s; 0 = the longest body motion
  int newton_iterations = 1;
  int iterations_after_damping = NewtonOptions{}.iterations_after_damping;  ///< NewtonOptions'
  bool line_search = false;
  std::optional<double> nonlinearity_tolerance;  ///< NewtonOptions'; unset = auto
  Vec3 gravity = Vec3(0, -9.81, 0);     ///< m/s²
  double damping = 0;                   ///< s
};

struct OutputDescription {
  std::string out = "result.h5";
  std::string export_path;              ///< "" = none
  std::string render;                   ///< "" = none
  int render_frames = 6;
  double fps = 30;
};

struct SceneDescription {
  std::string path;                     ///< the file it was read from ("" if built in code)
  std::vector<BodyDescription> bodies;
  std::vector<RigidObjectDescription> objects;
  std::vector<ToolDescription> tools;
  ContactDescription contact;
  SolverDescription solver;
  OutputDescription output;

  /// Index of the body / object named `name`, or -1.
  int body_index(const std::string& name) const;
  int object_index(const std::string& name) const;
  /// Whether bodies/objects `a` and `b` (names) collide under `contact`
  /// (all_pairs or listed in either order; object–object never).
  bool collides(const std::string& a, const std::string& b) const;
};

/// Reads and checks a scene file; relative input paths (avatar, motion,
/// material, mesh) are resolved against the file's folder and stored
/// absolute, output paths are kept as written. Throws one sflsh::Error
/// "FILE:LINE: KEY.PATH: message" on any bad input listed above.
SceneDescription read_scene_description(const std::string& path);
/// The same for YAML text in memory: `path` names the file in errors and its
/// folder resolves relative input paths (the file itself need not exist).
SceneDescription parse_scene_description(const std::string& yaml_text, const std::string& path);

/// The scene as YAML text in the format above (the keys of each object's
/// kind, numbers as the shortest decimals that read back to the same values,
/// input paths absolute).
std::string scene_description_yaml(const SceneDescription& scene);

/// Writes scene_description_yaml(scene) to `path` (atomic).
void write_scene_description(const SceneDescription& scene, const std::string& path);

}  // namespace sflsh
