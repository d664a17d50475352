// Scene files: the example scenes parse, every kind of bad input gets one
// error naming the file, the line and the key path, and a scene with a
// non-default value in every field survives a write/read round trip.
#include "sflsh/scene/scene_description.hpp"
#include "sflsh/scene_assets/scene_assets.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "sflsh/io/mesh_export.hpp"
#include "sflsh/scene/material_file.hpp"
#include "test_support.hpp"

namespace sflsh {
namespace {

namespace fs = std::filesystem;

/// A folder with the files scenes refer to: avatar.h5 (its content is not
/// read here), walk.bvh, soft.yaml, a closed ball.obj and an open cup.obj.
class SceneFolder {
 public:
  SceneFolder() {
    for (const char* name : {"avatar.h5", "walk.bvh", "soft.yaml"}) write(name, "placeholder\n");
    Points V(4, 3);
    V << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1;
    Triangles F(4, 3);
    F << 0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3;  // a closed tetrahedron
    io::write_mesh(dir_.file("ball.obj"), V, F);
    io::write_mesh(dir_.file("cup.obj"), V, Triangles(F.topRows(3)));
  }
  std::string write(const std::string& name, const std::string& text) const {
    std::ofstream(dir_.file(name)) << text;
    return dir_.file(name);
  }
  std::string file(const std::string& name) const { return dir_.file(name); }

 private:
  test::TempDir dir_;
};

/// Reading `text` (as scene.yaml) fails with one error holding every fragment.
void expect_scene_error(const std::string& text, std::initializer_list<std::string> fragments) {
  SceneFolder folder;
  const std::string path = folder.write("scene.yaml", text);
  test::expect_error([&] { read_scene_description(path); }, fragments);
}

TEST(SceneDescription, ExampleScenesParse) {
  // Every example scene, where it lies: it runs as written (avatar: default, the
  // built-in body, needs no file next to it).
  int scenes = 0;
  for (const char* dir : {"apps/scenes", "apps/scenes/figures"})
    for (const auto& e : fs::directory_iterator(fs::path(test::source_dir()) / dir)) {
      if (e.path().extension() != ".yaml") continue;
      ++scenes;
      const SceneDescription s = read_scene_description(e.path().string());
      ASSERT_FALSE(s.bodies.empty()) << e.path();
      for (const BodyDescription& b : s.bodies) {
        EXPECT_TRUE(b.default_avatar) << e.path() << " body " << b.name;
        EXPECT_EQ(b.avatar, "default") << e.path();
      }
    }
  EXPECT_GE(scenes, 12);
  SceneFolder folder;
  for (const char* name : {"ball_at_belly.yaml", "box_press.yaml", "two_walkers.yaml"})
    fs::copy_file(fs::path(test::source_dir()) / "apps" / "scenes" / name, folder.file(name));
  const SceneDescription ball = read_scene_description(folder.file("ball_at_belly.yaml"));
  ASSERT_EQ(ball.objects.size(), 1u);
  EXPECT_EQ(ball.objects[0].kind, ObjectKind::Dynamic);
  EXPECT_EQ(ball.objects[0].mass, 0.43);
  EXPECT_EQ(ball.solver.dt, 1.0 / 240);
  const SceneDescription walkers = read_scene_description(folder.file("two_walkers.yaml"));
  ASSERT_EQ(walkers.bodies.size(), 2u);
  EXPECT_EQ(walkers.bodies[1].heading_deg, 180);
  EXPECT_TRUE(walkers.collides("alice", "bob"));
  EXPECT_TRUE(walkers.objects.empty());
  const SceneDescription press = read_scene_description(folder.file("box_press.yaml"));
  EXPECT_EQ(press.objects[0].keyframes.size(), 4u);
  EXPECT_EQ(press.objects[0].position, Vec3(0, 1.05, 0.40));  // the first keyframe's
  EXPECT_TRUE(press.collides("press", "alice"));
}

TEST(SceneDescription, DefaultsAndRelativePaths) {
  SceneFolder folder;
  const std::string path = folder.write("s.yaml", R"(bodies:
  - name: alice
    avatar: avatar.h5
    motion: walk.bvh
    material: soft.yaml
objects:
  - name: chair
    shape: {type: mesh, file: ball.obj}
)");
  const SceneDescription s = read_scene_description(path);
  EXPECT_EQ(s.path, path);
  const auto& b = s.bodies.at(0);
  EXPECT_TRUE(fs::path(b.motion).is_absolute());
  EXPECT_EQ(fs::path(b.motion).filename(), "walk.bvh");
  EXPECT_EQ(fs::path(b.material).filename(), "soft.yaml");
  EXPECT_TRUE(b.bones_dynamic);
  EXPECT_EQ(b.offset, Vec3::Zero());
  const auto& o = s.objects.at(0);
  EXPECT_EQ(o.kind, ObjectKind::Static);
  EXPECT_EQ(o.shape.type, ShapeType::Mesh);
  EXPECT_EQ(o.shape.mesh_scale, 1.0);
  EXPECT_EQ(o.shape.voxel_size, 0.005);
  EXPECT_EQ(s.solver.dt, 1.0 / 60);
  EXPECT_EQ(s.solver.gravity, Vec3(0, -9.81, 0));
  EXPECT_FALSE(s.solver.nonlinearity_tolerance.has_value());  // auto
  EXPECT_EQ(s.output.out, "result.h5");
  EXPECT_TRUE(s.contact.all_pairs);
  EXPECT_NE(o.shape.location.find("s.yaml:8: objects[0].shape"), std::string::npos) << o.shape.location;
  SceneDescription baked = s;
  prepare_scene_assets(baked, "", false);  // ball.obj is closed: baked
  EXPECT_NE(baked.objects[0].shape.baked_sdf, nullptr);
}

TEST(SceneDescription, ToolsParseRoundTripAndRejectBadInput) {
  const std::string head = "bodies:\n  - {name: a, avatar: avatar.h5}\nsolver: {seconds: 1}\ntools:\n";
  SceneFolder folder;
  const std::string path = folder.write("scene.yaml", head + R"(  - name: pincher
    shape: {type: capsule, radius: 0.005, length: 0.03}
    keyframes:
      - {time: 0, position: [0.1, 1.1, 0.12], closure: 1.25}
      - {time: 0.5, position: [0.1, 1.2, 0.12], orientation: [0, 0, 1, 0], closure: 0.05}
    grasp:
      sensors: [{origin: [0, 0.01, 0], direction: [0, 0, -2], range: 0.015}]
      closure_threshold: 0.3
      hardness: 3.5e4
      damping: 2.5
)");
  const SceneDescription s = read_scene_description(path);
  ASSERT_EQ(s.tools.size(), 1u);
  const ToolDescription& t = s.tools[0];
  EXPECT_TRUE(t.has_shape);
  EXPECT_EQ(t.shape.type, ShapeType::Capsule);
  ASSERT_EQ(t.keyframes.size(), 2u);
  EXPECT_EQ(t.keyframes[1].position, Vec3(0.1, 1.2, 0.12));
  EXPECT_EQ(t.keyframes[1].closure, 0.05);
  EXPECT_EQ(t.keyframes[1].orientation.y(), 1.0);
  ASSERT_EQ(t.sensors.size(), 1u);
  EXPECT_EQ(t.sensors[0].direction, Vec3(0, 0, -1));  // normalized
  EXPECT_EQ(t.sensors[0].origin, Vec3(0, 0.01, 0));
  EXPECT_EQ(t.sensors[0].range, 0.015);
  EXPECT_EQ(t.closure_threshold, 0.3);
  EXPECT_EQ(t.hardness, 3.5e4);
  EXPECT_EQ(t.damping, 2.5);
  // Written and read back: the same tool.
  const std::string again = folder.write("again.yaml", scene_description_yaml(s));
  const SceneDescription r = read_scene_description(again);
  ASSERT_EQ(r.tools.size(), 1u);
  EXPECT_EQ(r.tools[0].keyframes[1].closure, 0.05);
  EXPECT_EQ(r.tools[0].sensors[0].range, 0.015);
  EXPECT_EQ(r.tools[0].hardness, 3.5e4);
  EXPECT_EQ(r.tools[0].shape.radius, 0.005);
  // Bad input: file, line, key path.
  expect_scene_error(head + "  - name: g\n    grasp: {sensors: [{direction: [0, 0, 1], range: 0.01}]}\n",
                     {"scene.yaml:5:", "tools[0]", "exactly one pose source"});
  expect_scene_error(head + "  - name: g\n    pose_file: nowhere.csv\n",
                     {"scene.yaml:6:", "tools[0].pose_file", "pose file not found"});
  expect_scene_error(head + "  - name: g\n    keyframes: [{time: 0, position: [0, 0, 0]}]\n"
                            "    grasp: {sensors: [{direction: [0, 0, 0], range: 0.01}]}\n",
                     {"scene.yaml:7:", "tools[0].grasp.sensors[0].direction", "must not be zero"});
  expect_scene_error(head + "  - name: a\n    keyframes: [{time: 0, position: [0, 0, 0]}]\n",
                     {"tools[0].name", "used twice"});
  expect_scene_error(head + "  - name: g\n    keyframes: [{time: 0, position: [0, 0, 0], closing: 1}]\n",
                     {"tools[0].keyframes[0].closing", "unknown key"});
}

TEST(SceneDescription, UnknownKeys) {
  expect_scene_error("bodies:\n  - name: a\n    avatar: avatar.h5\nsolver: {seconds: 1}\nobject: []\n",
                     {"scene.yaml:5:", "object", "unknown key 'object'", "objects"});
  expect_scene_error(R"(bodies:
  - name: a
    avatar: avatar.h5
solver: {seconds: 1}
objects:
  - name: b
    shape: {type: sphere, radius: 0.1}
  - name: c
    shape:
      type: sphere
      radus: 0.2
)",
                     {"scene.yaml:11:", "objects[1].shape.radus", "unknown key 'radus'", "expected: type, radius"});
  // A key that exists for other kinds only.
  expect_scene_error(R"(bodies:
  - name: a
    avatar: avatar.h5
solver: {seconds: 1}
objects:
  - name: floor
    shape: {type: plane}
    velocity: [0, 0, 1]
)",
                     {"scene.yaml:8:", "objects[0].velocity", "static object"});
}

TEST(SceneDescription, ListOrMapKeysAreErrorsAndTextParsesLikeTheFile) {
  // A flow list as a key made yaml-cpp's as<std::string>() throw its own exception.
  expect_scene_error("bodies:\n  - name: a\n    avatar: avatar.h5\n? [1, 2]\n: 3\n",
                     {"scene.yaml:4:", "expected a plain name as key"});
  // parse_scene_description: the same scene from memory, relative paths against the given path's folder.
  SceneFolder folder;
  const std::string text = "bodies:\n  - name: a\n    avatar: avatar.h5\nsolver: {seconds: 1}\n";
  const SceneDescription from_file = read_scene_description(folder.write("scene.yaml", text));
  const SceneDescription from_text = parse_scene_description(text, folder.file("in-memory.yaml"));
  EXPECT_EQ(from_text.bodies.at(0).avatar, from_file.bodies.at(0).avatar);
  EXPECT_EQ(from_text.solver.seconds, 1.0);
  test::expect_error([&] { parse_scene_description("bodies: [", folder.file("in-memory.yaml")); },
                     {"in-memory.yaml:1:", "malformed YAML"});
  // Material text: the same rule for keys.
  std::vector<RegionMaterial> materials(1);
  materials[0].name = "belly";
  test::expect_error([&] { apply_material_text("regions:\n  ? {a: 1}\n  : {young: 1}\n", "m.yaml", materials); },
                     {"m.yaml:2:", "expected a plain name as key"});
  apply_material_text("regions: {belly: {young: 2.5e4}}\n", "m.yaml", materials);
  EXPECT_EQ(materials[0].young_through, 2.5e4);
}

TEST(SceneDescription, MissingRequiredKeys) {
  expect_scene_error("solver: {seconds: 1}\n", {"scene.yaml:1:", "bodies", "missing required key 'bodies'"});
  expect_scene_error("bodies:\n  - name: a\n    motion: builtin:walk\n",
                     {"scene.yaml:2:", "bodies[0].avatar", "missing required key 'avatar'"});
  expect_scene_error(R"(bodies:
  - name: a
    avatar: avatar.h5
solver: {seconds: 1}
objects:
  - name: ball
    shape: {type: sphere}
)",
                     {"scene.yaml:7:", "objects[0].shape.radius", "missing required key 'radius'"});
  expect_scene_error(R"(bodies:
  - name: a
    avatar: avatar.h5
solver: {seconds: 1}
objects:
  - name: ball
    shape: {type: sphere, radius: 0.1}
    kind: dynamic
)",
                     {"scene.yaml:6:", "objects[0]", "exactly one of 'density'"});
}

TEST(SceneDescription, WrongTypes) {
  expect_scene_error(R"(bodies:
  - name: a
    avatar: avatar.h5
solver: {seconds: 1}
objects:
  - name: ball
    shape: {type: sphere, radius: big}
)",
                     {"scene.yaml:7:", "objects[0].shape.radius", "expected a number, got 'big'"});
  expect_scene_error("bodies:\n  - name: a\n    avatar: avatar.h5\n    placement: {offset: [1, 2]}\nsolver: {seconds: 1}\n",
                     {"scene.yaml:4:", "bodies[0].placement.offset", "list of 3 numbers"});
  expect_scene_error("bodies:\n  - name: a\n    avatar: avatar.h5\nsolver: {seconds: 1, line_search: maybe}\n",
                     {"scene.yaml:4:", "solver.line_search", "true or false"});
  expect_scene_error("bodies:\n  - name: a\n    avatar: avatar.h5\nsolver: {seconds: 1, nonlinearity_tolerance: -0.1}\n",
                     {"scene.yaml:4:", "solver.nonlinearity_tolerance"});
  expect_scene_error("bodies:\n  - name: a\n    avatar: avatar.h5\nsolver: {seconds: 1, newton_iters: 1.5}\n",
                     {"scene.yaml:4:", "solver.newton_iters", "integer"});
  expect_scene_error("bodies: {name: a}\n", {"scene.yaml:1:", "bodies", "list of at least one body"});
  expect_scene_error("bodies:\n  - name: a\n    avatar: avatar.h5\nsolver: {dt: fast, seconds: 1}\n",
                     {"scene.yaml:4:", "solver.dt", "expected a time step", "'fast'"});
  expect_scene_error("bodies: [\n", {"scene.yaml:", "malformed YAML"});
}

TEST(SceneDescription, NegativeAndNonFiniteValues) {
  // Lines 1-6 of each scene; the object's keys follow from line 7.
  const std::string head = "bodies:\n  - name: a\n    avatar: avatar.h5\nsolver: {seconds: 1}\nobjects:\n  - name: o\n";
  struct Case {
    std::string object, line, key, message;
  };
  const std::vector<Case> cases = {
      {"    shape: {type: sphere, radius: 0.1}\n    kind: dynamic\n    mass: -2\n",
       "scene.yaml:9:", "objects[0].mass", "must be > 0, got -2"},
      {"    shape: {type: capsule, radius: -0.1, length: 0.3}\n",
       "scene.yaml:7:", "objects[0].shape.radius", "must be > 0, got -0.1"},
      {"    shape: {type: box, size: [0.1, -0.2, 0.3]}\n    kind: dynamic\n    density: 500\n",
       "scene.yaml:7:", "objects[0].shape.size[1]", "must be > 0"},
      {"    shape: {type: cylinder, radius: 0.1, length: 0.2}\n    kind: dynamic\n    density: -5\n",
       "scene.yaml:9:", "objects[0].density", "must be > 0, got -5"},
      {"    shape: {type: sphere, radius: .nan}\n", "scene.yaml:7:", "objects[0].shape.radius", "must be finite"},
      {"    shape: {type: sphere, radius: 0.1}\n    position: [0, .inf, 0]\n",
       "scene.yaml:8:", "objects[0].position[1]", "must be finite"},
      {"    shape: {type: sphere, radius: 0.1}\n    orientation: [0, 0, 90, 0]\n",
       "scene.yaml:8:", "objects[0].orientation", "unit quaternion"},
      {"    shape: {type: plane}\n    kind: dynamic\n    mass: 1\n",
       "scene.yaml:8:", "objects[0].kind", "plane cannot be dynamic"},
      {"    shape: {type: sphere, radius: 0.1}\n    kind: kinematic\n    keyframes:\n"
       "      - {time: 1, position: [0, 0, 0]}\n      - {time: 0.5, position: [0, 0, 1]}\n",
       "scene.yaml:11:", "objects[0].keyframes[1].time", "must increase"},
  };
  for (const Case& c : cases) expect_scene_error(head + c.object, {c.line, c.key, c.message});
  expect_scene_error("bodies:\n  - name: a\n    avatar: avatar.h5\ncontact: {stiffness: {body_body: -1}}\nsolver: {seconds: 1}\n",
                     {"scene.yaml:4:", "contact.stiffness.body_body", ">= 0"});
  expect_scene_error("bodies:\n  - name: a\n    avatar: avatar.h5\n", {"scene.yaml:1:", "solver.seconds", "no body has a motion"});
}

TEST(SceneDescription, PairsMustNameExistingBodiesOrObjects) {
  const std::string head =
      "bodies:\n  - name: alice\n    avatar: avatar.h5\nsolver: {seconds: 1}\n"
      "objects:\n  - name: floor\n    shape: {type: plane}\n  - name: wall\n    shape: {type: plane, normal: [1, 0, 0]}\n";
  expect_scene_error(head + "contact:\n  pairs: [[alice, floor], [alice, ball]]\n",
                     {"scene.yaml:11:", "contact.pairs[1][1]", "no body or object named 'ball'", "alice, floor, wall"});
  expect_scene_error(head + "contact:\n  pairs: [[floor, wall]]\n", {"scene.yaml:11:", "contact.pairs[0]", "both rigid objects"});
  expect_scene_error(head + "contact:\n  pairs: [[alice, alice]]\n", {"contact.pairs[0]", "self_contact"});
  expect_scene_error(head + "contact:\n  pairs: [[alice, floor], [floor, alice]]\n", {"contact.pairs[1]", "listed twice"});
  expect_scene_error(head + "contact:\n  pairs: some\n", {"scene.yaml:11:", "contact.pairs", "'all' or a list"});
  expect_scene_error(head + "  - name: alice\n    shape: {type: sphere, radius: 1}\n",
                     {"scene.yaml:10:", "objects[2].name", "'alice' is used twice"});
  SceneFolder folder;
  const SceneDescription s = read_scene_description(folder.write("s.yaml", head + "contact:\n  pairs: [[floor, alice]]\n"));
  EXPECT_TRUE(s.collides("alice", "floor"));
  EXPECT_FALSE(s.collides("alice", "wall"));
  EXPECT_FALSE(s.collides("floor", "wall"));
}

TEST(SceneDescription, MissingFiles) {
  expect_scene_error("bodies:\n  - name: a\n    avatar: avatars/none.h5\nsolver: {seconds: 1}\n",
                     {"scene.yaml:3:", "bodies[0].avatar", "avatar file not found", "avatars/none.h5", "sflsh precompute"});
  expect_scene_error("bodies:\n  - name: a\n    avatar: avatar.h5\n    motion: run.bvh\n",
                     {"scene.yaml:4:", "bodies[0].motion", "motion file not found", "run.bvh"});
  expect_scene_error("bodies:\n  - name: a\n    avatar: avatar.h5\n    motion: builtin:fly\n",
                     {"scene.yaml:4:", "bodies[0].motion", "unknown built-in motion 'builtin:fly'", "walk"});
  expect_scene_error(
      "bodies:\n  - name: a\n    avatar: avatar.h5\nsolver: {seconds: 1}\nobjects:\n  - name: chair\n"
      "    shape: {type: mesh, file: chair.stl}\n",
      {"scene.yaml:7:", "objects[0].shape.file", "mesh file not found", "chair.stl"});
  expect_scene_error("bodies:\n  - name: a\n    avatar: avatar.h5\n    material: hard.yaml\nsolver: {seconds: 1}\n",
                     {"scene.yaml:4:", "bodies[0].material", "material file not found"});
  test::expect_error([] { read_scene_description("/nonexistent/scene.yaml"); }, {"/nonexistent/scene.yaml", "not found"});
}

TEST(SceneDescription, NonClosedMeshIsRejectedWhenTheSceneIsPrepared) {
  SceneFolder folder;
  const std::string path = folder.write("s.yaml",
                                        "bodies:\n  - name: a\n    avatar: avatar.h5\nsolver: {seconds: 1}\nobjects:\n"
                                        "  - name: cup\n    shape: {type: mesh, file: cup.obj}\n");
  SceneDescription s = read_scene_description(path);  // reading does not open meshes
  test::expect_error([&] { prepare_scene_assets(s, "", false); },
                     {"s.yaml:7:", "objects[0].shape", "cup.obj", "closed", "3 boundary edges"});
}

/// A scene with a value different from the default in every field.
SceneDescription full_scene(const SceneFolder& folder) {
  SceneDescription s;
  BodyDescription a;
  a.name = "alice";
  a.avatar = folder.file("avatar.h5");
  a.motion = folder.file("walk.bvh");
  a.offset = Vec3(0.5, 0.25, -1.5);
  a.heading_deg = 37.5;
  a.bones_dynamic = false;
  a.material = folder.file("soft.yaml");
  a.velocity = Vec3(0.1, 0.2, 0.3);
  BodyDescription b = a;
  b.name = "bob";
  b.motion = "builtin:jump";
  b.material.clear();
  s.bodies = {a, b};

  auto object = [](const std::string& name, ShapeType type, ObjectKind kind) {
    RigidObjectDescription o;
    o.name = name;
    o.shape.type = type;
    o.kind = kind;
    return o;
  };
  RigidObjectDescription floor = object("floor", ShapeType::Plane, ObjectKind::Static);
  floor.shape.normal = Vec3(0, 0.6, 0.8);
  floor.position = Vec3(0, -1.25, 0);
  floor.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Vec3::UnitZ()));
  RigidObjectDescription ball = object("ball", ShapeType::Sphere, ObjectKind::Dynamic);
  ball.shape.radius = 0.11;
  ball.mass = 0.43;
  ball.position = Vec3(0, 0.1, 1);
  ball.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(1.1, Vec3(1, 2, 3).normalized()));
  ball.velocity = Vec3(0, 1, -6);
  ball.angular_velocity = Vec3(3, 2, 1);
  RigidObjectDescription crate = object("crate", ShapeType::Box, ObjectKind::Dynamic);
  crate.shape.size = Vec3(0.3, 0.2, 0.1);
  crate.density = 450;
  crate.position = Vec3(1, 2, 3);
  crate.orientation = Eigen::Quaterniond(0.5, 0.5, 0.5, 0.5);
  RigidObjectDescription bar = object("bar", ShapeType::Capsule, ObjectKind::Kinematic);
  bar.shape.radius = 0.04;
  bar.shape.length = 0.6;
  bar.keyframes = {{0.25, Vec3(0, 1, 0.5), Eigen::Quaterniond(Eigen::AngleAxisd(0.2, Vec3::UnitX()))},
                   {1.75, Vec3(0, 0.8, 0.2), Eigen::Quaterniond(Eigen::AngleAxisd(-0.4, Vec3::UnitY()))}};
  bar.position = bar.keyframes[0].position;
  bar.orientation = bar.keyframes[0].orientation;
  RigidObjectDescription post = object("post", ShapeType::Cylinder, ObjectKind::Static);
  post.shape.radius = 0.05;
  post.shape.length = 1.2;
  post.position = Vec3(-1, 0, 0);
  post.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(0.5 * 3.141592653589793, Vec3::UnitX()));
  RigidObjectDescription chair = object("chair", ShapeType::Mesh, ObjectKind::Static);
  chair.shape.mesh_file = folder.file("ball.obj");
  chair.shape.mesh_scale = 0.01;
  chair.shape.voxel_size = 0.004;
  chair.shape.padding = 0.03;
  chair.shape.band = 0.015;
  chair.position = Vec3(0.7, -0.8, 0.1);
  chair.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(-2.0, Vec3::UnitY()));
  s.objects = {floor, ball, crate, bar, post, chair};

  s.contact.body_object_stiffness = 3.5e4;
  s.contact.friction = 0.35;
  s.contact.body_body_stiffness = 7.5e3;
  s.contact.self_stiffness = 1.25e3;
  s.contact.self_contact = true;
  s.contact.sample_spacing = 0.015;
  s.contact.all_pairs = false;
  s.contact.pairs = {{"alice", "floor"}, {"ball", "alice"}, {"alice", "bob"}};
  s.contact.body_model = ContactDescription::BodyModel::Capsules;
  s.contact.body_pressure_stiffness = 2.5e8;
  s.contact.body_spacing = 0.012;
  s.contact.core_radius = 0.625;

  s.solver.dt = 1.0 / 90;
  s.solver.seconds = 2.5;
  s.solver.newton_iterations = 4;
  s.solver.iterations_after_damping = 7;
  s.solver.line_search = true;
  s.solver.nonlinearity_tolerance = 0.0625;
  s.solver.gravity = Vec3(0.1, -3.7, 0.2);
  s.solver.damping = 0.002;

  s.output.out = "out/run.h5";
  s.output.export_path = "out/run.glb";
  s.output.render = "out/run.png";
  s.output.render_frames = 9;
  s.output.fps = 24;
  return s;
}

// EXPECT that field `f` survived (a.f == b.f) and differs from its default (d.f).
#define EXPECT_FIELD(f)   \
  EXPECT_EQ(a.f, b.f);    \
  EXPECT_NE(a.f, d.f)

void expect_same_non_default(const BodyDescription& a, const BodyDescription& b) {
  const BodyDescription d;
  EXPECT_FIELD(name);
  EXPECT_FIELD(avatar);
  EXPECT_FIELD(motion);
  EXPECT_FIELD(offset);
  EXPECT_FIELD(heading_deg);
  EXPECT_FIELD(bones_dynamic);
  EXPECT_EQ(a.material, b.material);  // bob has none
  EXPECT_FIELD(velocity);
}

void expect_same_non_default(const Keyframe& a, const Keyframe& b) {
  const Keyframe d;
  EXPECT_FIELD(time);
  EXPECT_FIELD(position);
  EXPECT_FIELD(orientation.coeffs());
}

void expect_same_non_default(const ShapeDescription& a, const ShapeDescription& b) {
  const ShapeDescription d;
  EXPECT_EQ(a.type, b.type);
  switch (a.type) {
    case ShapeType::Plane: EXPECT_FIELD(normal); break;
    case ShapeType::Sphere: EXPECT_FIELD(radius); break;
    case ShapeType::Box: EXPECT_FIELD(size); break;
    case ShapeType::Capsule:
    case ShapeType::Cylinder:
      EXPECT_FIELD(radius);
      EXPECT_FIELD(length);
      break;
    case ShapeType::Mesh:
      EXPECT_FIELD(mesh_file);
      EXPECT_FIELD(mesh_scale);
      EXPECT_FIELD(voxel_size);
      EXPECT_FIELD(padding);
      EXPECT_FIELD(band);
      break;
  }
}

void expect_same_non_default(const RigidObjectDescription& a, const RigidObjectDescription& b) {
  const RigidObjectDescription d;
  EXPECT_FIELD(name);
  expect_same_non_default(a.shape, b.shape);
  EXPECT_EQ(a.kind, b.kind);
  EXPECT_FIELD(position);
  EXPECT_FIELD(orientation.coeffs());
  ASSERT_EQ(a.keyframes.size(), b.keyframes.size());
  for (std::size_t i = 0; i < a.keyframes.size(); ++i) expect_same_non_default(a.keyframes[i], b.keyframes[i]);
  if (a.kind == ObjectKind::Dynamic) {
    EXPECT_EQ(a.density, b.density);
    EXPECT_EQ(a.mass, b.mass);
    EXPECT_NE(a.density + a.mass, 0.0);
  }
  EXPECT_EQ(a.velocity, b.velocity);
  EXPECT_EQ(a.angular_velocity, b.angular_velocity);
}

/// solver.nonlinearity_tolerance: "auto" (or absent) leaves it unset, a number sets it, and an
/// unset one is written as "auto" and read back unset.
TEST(SceneDescription, NonlinearityToleranceIsAutoOrANumber) {
  SceneFolder folder;
  const std::string body = "bodies:\n  - name: a\n    avatar: avatar.h5\n";
  const SceneDescription a =
      parse_scene_description(body + "solver: {seconds: 1, nonlinearity_tolerance: auto}\n", folder.file("a.yaml"));
  EXPECT_FALSE(a.solver.nonlinearity_tolerance.has_value());
  const SceneDescription n =
      parse_scene_description(body + "solver: {seconds: 1, nonlinearity_tolerance: 0.125}\n", folder.file("n.yaml"));
  EXPECT_EQ(n.solver.nonlinearity_tolerance, 0.125);
  // 0 is the documented "off" (no iteration added for nonlinearity), not an error.
  const SceneDescription off =
      parse_scene_description(body + "solver: {seconds: 1, nonlinearity_tolerance: 0}\n", folder.file("o.yaml"));
  ASSERT_TRUE(off.solver.nonlinearity_tolerance.has_value());
  EXPECT_EQ(*off.solver.nonlinearity_tolerance, 0.0);
  write_scene_description(a, folder.file("auto.yaml"));
  std::ifstream f(folder.file("auto.yaml"));
  const std::string text((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("nonlinearity_tolerance: auto"), std::string::npos) << text;
  EXPECT_FALSE(read_scene_description(folder.file("auto.yaml")).solver.nonlinearity_tolerance.has_value());
  expect_scene_error(body + "solver: {seconds: 1, nonlinearity_tolerance: sometimes}\n",
                     {"scene.yaml:4:", "solver.nonlinearity_tolerance", "auto or a number >= 0", "sometimes"});
  expect_scene_error(body + "solver: {seconds: 1, nonlinearity_tolerance: -0.5}\n",
                     {"scene.yaml:4:", "solver.nonlinearity_tolerance", "auto or a number >= 0", "-0.5"});
}

TEST(SceneDescription, FullRoundTripKeepsEveryField) {
  SceneFolder folder;
  const SceneDescription a = full_scene(folder);
  write_scene_description(a, folder.file("full.yaml"));
  const SceneDescription b = read_scene_description(folder.file("full.yaml"));
  const SceneDescription d;
  ASSERT_EQ(b.bodies.size(), 2u);
  for (int i = 0; i < 2; ++i) expect_same_non_default(a.bodies[i], b.bodies[i]);
  EXPECT_NE(a.bodies[0].material, "");
  ASSERT_EQ(b.objects.size(), a.objects.size());
  for (std::size_t i = 0; i < a.objects.size(); ++i) expect_same_non_default(a.objects[i], b.objects[i]);
  EXPECT_FIELD(contact.body_object_stiffness);
  EXPECT_FIELD(contact.friction);
  EXPECT_FIELD(contact.body_body_stiffness);
  EXPECT_FIELD(contact.self_stiffness);
  EXPECT_FIELD(contact.self_contact);
  EXPECT_FIELD(contact.sample_spacing);
  EXPECT_FIELD(contact.all_pairs);
  EXPECT_FIELD(contact.pairs);
  EXPECT_FIELD(contact.body_model);
  EXPECT_FIELD(contact.body_pressure_stiffness);
  EXPECT_FIELD(contact.body_spacing);
  EXPECT_FIELD(contact.core_radius);
  EXPECT_FIELD(solver.dt);
  EXPECT_FIELD(solver.seconds);
  EXPECT_FIELD(solver.newton_iterations);
  EXPECT_FIELD(solver.iterations_after_damping);
  EXPECT_FIELD(solver.line_search);
  EXPECT_FIELD(solver.nonlinearity_tolerance);
  EXPECT_FIELD(solver.gravity);
  EXPECT_FIELD(solver.damping);
  EXPECT_FIELD(output.out);
  EXPECT_FIELD(output.export_path);
  EXPECT_FIELD(output.render);
  EXPECT_FIELD(output.render_frames);
  EXPECT_FIELD(output.fps);
  // Writing what was read gives the same text.
  EXPECT_EQ(scene_description_yaml(b), scene_description_yaml(a));
}

}  // namespace
}  // namespace sflsh

namespace sflsh {
namespace {

// contact.patch: off by default; a map turns it on with its settings (each
// distinct from the default), written back and read again the same; refused
// with friction, with a radius <= 0 and with a word that is not a boolean.
TEST(SceneDescription, ContactPatchKeysParseWriteBackAndRefuseBadValues) {
  const std::string body = "bodies:\n  - name: a\n    avatar: avatar.h5\nsolver: {seconds: 1}\n";
  SceneFolder folder;
  const SceneDescription off = parse_scene_description(body, folder.file("off.yaml"));
  EXPECT_FALSE(off.contact.patch);
  const SceneDescription on = parse_scene_description(
      body + "contact: {friction: 0, patch: {radius: 0.03, max_nodes: 777, pressure_stiffness: 5.0e7, spacing: 0.003}}\n",
      folder.file("on.yaml"));
  const ContactDescription d;
  EXPECT_TRUE(on.contact.patch);
  EXPECT_EQ(on.contact.patch_radius, 0.03);
  EXPECT_EQ(on.contact.max_patch_nodes, 777);
  EXPECT_NE(d.max_patch_nodes, 777);
  EXPECT_EQ(on.contact.pressure_stiffness, 5.0e7);
  EXPECT_EQ(on.contact.patch_spacing, 0.003);
  EXPECT_NE(on.contact.patch_radius, d.patch_radius);
  EXPECT_NE(on.contact.pressure_stiffness, d.pressure_stiffness);
  EXPECT_NE(on.contact.patch_spacing, d.patch_spacing);
  const SceneDescription again = parse_scene_description(scene_description_yaml(on), folder.file("again.yaml"));
  EXPECT_TRUE(again.contact.patch);
  EXPECT_EQ(again.contact.patch_radius, 0.03);
  EXPECT_EQ(again.contact.max_patch_nodes, 777);
  EXPECT_EQ(again.contact.pressure_stiffness, 5.0e7);
  EXPECT_EQ(again.contact.patch_spacing, 0.003);
  EXPECT_TRUE(parse_scene_description(body + "contact: {friction: 0, patch: true}\n", folder.file("t.yaml")).contact.patch);
  {
    // The patch takes the scene's friction (default 0.5).
    const SceneDescription with_friction = parse_scene_description(body + "contact: {patch: true}\n", folder.file("f.yaml"));
    EXPECT_TRUE(with_friction.contact.patch);
    EXPECT_EQ(with_friction.contact.friction, 0.5);
  }
  expect_scene_error(body + "contact: {friction: 0, patch: {radius: 0}}\n", {"scene.yaml:5:", "contact.patch.radius"});
  expect_scene_error(body + "contact: {friction: 0, patch: {max_nodes: 0}}\n", {"scene.yaml:5:", "contact.patch.max_nodes"});
  expect_scene_error(body + "contact: {friction: 0, patch: {max_nodes: 2.5}}\n",
                     {"scene.yaml:5:", "contact.patch.max_nodes", "integer"});
  expect_scene_error(body + "contact: {friction: 0, patch: {pressure_stiffness: -1}}\n",
                     {"scene.yaml:5:", "contact.patch.pressure_stiffness"});
  expect_scene_error(body + "contact: {friction: 0, patch: maybe}\n", {"scene.yaml:5:", "contact.patch", "true or false"});
  expect_scene_error(body + "contact: {friction: 0, patch: {size: 1}}\n", {"scene.yaml:5:", "contact.patch", "size"});
}

// contact.bodies: skin by default; each key distinct from its default, written
// back and read again the same; a model that is not skin or capsules, a
// pressure stiffness or spacing <= 0 and a core radius outside (0, 1] refused.
TEST(SceneDescription, BodyContactKeysParseWriteBackAndRefuseBadValues) {
  const std::string body = "bodies:\n  - name: a\n    avatar: avatar.h5\nsolver: {seconds: 1}\n";
  SceneFolder folder;
  const ContactDescription d;
  EXPECT_EQ(d.body_model, ContactDescription::BodyModel::Skin);
  const SceneDescription set = parse_scene_description(
      body + "contact: {bodies: {model: capsules, pressure_stiffness: 3.0e8, spacing: 0.006, core_radius: 0.7}}\n",
      folder.file("set.yaml"));
  for (const SceneDescription& s :
       {set, parse_scene_description(scene_description_yaml(set), folder.file("again.yaml"))}) {
    EXPECT_EQ(s.contact.body_model, ContactDescription::BodyModel::Capsules);
    EXPECT_EQ(s.contact.body_pressure_stiffness, 3.0e8);
    EXPECT_EQ(s.contact.body_spacing, 0.006);
    EXPECT_EQ(s.contact.core_radius, 0.7);
  }
  EXPECT_NE(d.body_pressure_stiffness, 3.0e8);
  EXPECT_NE(d.body_spacing, 0.006);
  EXPECT_NE(d.core_radius, 0.7);
  expect_scene_error(body + "contact: {bodies: {model: jelly}}\n", {"scene.yaml:5:", "contact.bodies.model", "'jelly'"});
  expect_scene_error(body + "contact: {bodies: {pressure_stiffness: 0}}\n",
                     {"scene.yaml:5:", "contact.bodies.pressure_stiffness"});
  expect_scene_error(body + "contact: {bodies: {spacing: -0.01}}\n", {"scene.yaml:5:", "contact.bodies.spacing"});
  expect_scene_error(body + "contact: {bodies: {core_radius: 1.5}}\n", {"scene.yaml:5:", "contact.bodies.core_radius", "(0, 1]"});
  expect_scene_error(body + "contact: {bodies: {core_radius: .nan}}\n", {"scene.yaml:5:", "contact.bodies.core_radius"});
  expect_scene_error(body + "contact: {bodies: {size: 1}}\n", {"scene.yaml:5:", "contact.bodies", "size"});
}

TEST(SceneDescription, PoseStreamRampInParsesWritesBackAndRefusesNegatives) {
  SceneFolder folder;
  const std::string head = "bodies:\n  - {name: a, avatar: avatar.h5}\nsolver: {seconds: 1}\ntools:\n";
  const SceneDescription d = parse_scene_description(head + "  - {name: t, pose_stream: {port: 0}}\n",
                                                     folder.file("d.yaml"));
  EXPECT_EQ(d.tools.at(0).stream_ramp_in, 0.5);  // the documented default
  const SceneDescription s = parse_scene_description(
      head + "  - {name: t, pose_stream: {port: 0, max_speed: 3, ramp_in: 0.25}}\n", folder.file("s.yaml"));
  EXPECT_EQ(s.tools.at(0).stream_ramp_in, 0.25);
  EXPECT_EQ(s.tools.at(0).stream_max_speed, 3.0);
  const SceneDescription off = parse_scene_description(
      head + "  - {name: t, pose_stream: {port: 0, ramp_in: 0}}\n", folder.file("o.yaml"));
  EXPECT_EQ(off.tools.at(0).stream_ramp_in, 0.0);  // 0: the device takes over at once
  write_scene_description(s, folder.file("again.yaml"));
  EXPECT_EQ(read_scene_description(folder.file("again.yaml")).tools.at(0).stream_ramp_in, 0.25);
  expect_scene_error(head + "  - {name: t, pose_stream: {port: 0, ramp_in: -0.5}}\n",
                     {"tools[0].pose_stream.ramp_in", "-0.5"});
}

TEST(SceneDescription, DefaultAvatarWithBetasParsesWritesBackAndRefusesBadBetas) {
  SceneFolder folder;
  const SceneDescription s = parse_scene_description(
      "bodies:\n  - {name: a, avatar: default, betas: [1.5, -1]}\n  - {name: b, avatar: default}\n"
      "solver: {seconds: 1}\n",
      folder.file("d.yaml"));
  ASSERT_EQ(s.bodies.size(), 2u);
  EXPECT_TRUE(s.bodies[0].default_avatar);
  EXPECT_EQ(s.bodies[0].avatar, "default");  // resolved by the commands (precompute/cached_avatar.hpp)
  ASSERT_EQ(s.bodies[0].betas.size(), 2);
  EXPECT_EQ(s.bodies[0].betas[0], 1.5);
  EXPECT_EQ(s.bodies[0].betas[1], -1.0);
  EXPECT_EQ(s.bodies[1].betas.size(), 0);
  write_scene_description(s, folder.file("again.yaml"));
  const SceneDescription r = read_scene_description(folder.file("again.yaml"));
  EXPECT_TRUE(r.bodies[0].default_avatar);
  EXPECT_EQ(r.bodies[0].betas, s.bodies[0].betas);
  const std::string bodies = "solver: {seconds: 1}\nbodies:\n";
  expect_scene_error(bodies + "  - {name: a, avatar: avatar.h5, betas: [1]}\n",
                     {"bodies[0].betas", "avatar: default only"});
  expect_scene_error(bodies + "  - {name: a, avatar: default, betas: [1, .nan]}\n", {"bodies[0].betas[1]", "finite"});
  expect_scene_error(bodies + "  - {name: a, avatar: default, betas: [0,0,0,0,0,0,0,0,0,0,0]}\n",
                     {"bodies[0].betas", "1 to 10 numbers"});
  expect_scene_error(bodies + "  - {name: a, avatar: default, betas: []}\n", {"bodies[0].betas", "1 to 10 numbers"});
}

}  // namespace
}  // namespace sflsh
