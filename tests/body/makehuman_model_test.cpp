// The MakeHuman base human converted to an SMPL-format model
// (data_tools/makehuman_to_smpl.py), checked against the MakeHuman files read
// here independently: the surface, the joint groups' centres, the bone weights
// and the shape targets. Skips when ../shared/data/makehuman is absent.
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <set>
#include <sstream>

#include "sflsh/body/body_model.hpp"
#include "sflsh/body/body_model_io.hpp"
#include "sflsh/meshing/surface_checks.hpp"
#include "test_support.hpp"

namespace sflsh {
namespace {

constexpr int kBodyVertices = 13380;  // hm08: the `body` group is vertices 0..13379

// base.obj: every vertex (decimetres) and the vertex set of each group.
struct Obj {
  std::vector<Vec3> v;
  std::map<std::string, std::set<int>> groups;
};

Obj read_obj(const std::string& path) {
  Obj o;
  std::ifstream in(path);
  std::string line, group;
  while (std::getline(in, line)) {
    std::istringstream ls(line);
    std::string tag;
    ls >> tag;
    if (tag == "v") {
      Vec3 p;
      ls >> p.x() >> p.y() >> p.z();
      o.v.push_back(p);
    } else if (tag == "g") {
      ls >> group;
    } else if (tag == "f") {
      std::string t;
      while (ls >> t) o.groups[group].insert(std::stoi(t.substr(0, t.find('/'))) - 1);
    }
  }
  return o;
}

// A MakeHuman target: dense offsets (decimetres) for the first `n` vertices.
Points read_target(const std::string& path, int n) {
  Points off = Points::Zero(n, 3);
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream ls(line);
    int i;
    Vec3 d;
    ls >> i >> d.x() >> d.y() >> d.z();
    if (i < n) off.row(i) = d.transpose();
  }
  return off;
}

// default_weights.mhw: bone -> (vertex, weight) pairs, by scanning the text
// (`"bone": [ [v, w], ... ]`), no JSON library.
std::map<std::string, std::vector<std::pair<int, double>>> read_bone_weights(const std::string& path) {
  std::ifstream in(path);
  const std::string s((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::map<std::string, std::vector<std::pair<int, double>>> out;
  size_t pos = s.find("\"weights\"");
  while ((pos = s.find('"', pos + 1)) != std::string::npos) {
    const size_t end = s.find('"', pos + 1);
    const std::string name = s.substr(pos + 1, end - pos - 1);
    size_t open = s.find('[', end);
    if (open == std::string::npos) break;
    size_t close = open + 1;
    int depth = 1;
    while (depth > 0 && close < s.size()) depth += s[close] == '[' ? 1 : s[close] == ']' ? -1 : 0, ++close;
    std::string body = s.substr(open + 1, close - open - 2);
    for (char& c : body)
      if (c == '[' || c == ']' || c == ',') c = ' ';
    std::istringstream ls(body);
    int v;
    double w;
    while (ls >> v >> w) out[name].emplace_back(v, w);
    pos = close;
  }
  return out;
}

class MakeHumanModel : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    folder_ = test::shared_data("makehuman");
    if (folder_.empty()) return;
    dir_ = std::make_unique<test::TempDir>();
    const std::string out = dir_->file("mh.h5");
    std::string log;
    const int rc = test::run_command("/usr/bin/python3 " + test::source_dir() + "/data_tools/makehuman_to_smpl.py " +
                                         folder_ + " " + out,
                                     &log);
    ASSERT_EQ(rc, 0) << log;
    model_ = std::make_unique<BodyModel>(read_body_model_hdf5(out));
    obj_ = std::make_unique<Obj>(read_obj(folder_ + "/base.obj"));
  }
  static void TearDownTestSuite() {
    model_.reset();
    obj_.reset();
    dir_.reset();
  }
  void SetUp() override {
    if (folder_.empty())
      GTEST_SKIP() << "../shared/data/makehuman is absent (the MakeHuman base human); skipping the converter checks";
    ASSERT_TRUE(model_) << "the conversion failed (see the first test's output)";
  }
  // Centre of a joint-* group of base.obj in metres.
  static Vec3 group_centre(const std::string& g) {
    const auto it = obj_->groups.find(g);
    EXPECT_NE(it, obj_->groups.end()) << g;
    Vec3 c = Vec3::Zero();
    for (int i : it->second) c += obj_->v[i];
    return 0.1 * c / double(it->second.size());
  }
  static Points base_metres() {
    Points b(kBodyVertices, 3);
    for (int i = 0; i < kBodyVertices; ++i) b.row(i) = 0.1 * obj_->v[i].transpose();
    return b;
  }

  static inline std::string folder_;
  static inline std::unique_ptr<test::TempDir> dir_;
  static inline std::unique_ptr<BodyModel> model_;
  static inline std::unique_ptr<Obj> obj_;
};

TEST_F(MakeHumanModel, SurfaceIsClosedManifoldOrientedAndFreeOfSelfIntersections) {
  const SurfaceReport r = check_surface(model_->v_template, model_->faces, true);
  EXPECT_TRUE(r.is_closed) << r.describe();
  EXPECT_TRUE(r.is_manifold) << r.describe();
  EXPECT_TRUE(r.consistently_oriented) << r.describe();
  EXPECT_EQ(r.num_components, 1);
  EXPECT_EQ(r.genus, 0);
  EXPECT_GT(r.signed_volume, 0.0);
  EXPECT_TRUE(r.self_intersection_tested);
  EXPECT_FALSE(r.self_intersects);
  // Only the body group, in metres: 1.666 m tall (base.obj: -8.1676 .. 8.4913 dm).
  EXPECT_EQ(model_->num_vertices(), kBodyVertices);
  EXPECT_EQ(model_->faces.rows(), 2 * 13378);  // 13378 quads, two triangles each
  EXPECT_NEAR(r.height(), 0.84913 + 0.81676, 1e-9);
}

TEST_F(MakeHumanModel, JointsWithinOneCentimetreOfTheJointGroupCentres) {
  // SMPL joint -> base.obj joint-* groups (the documented mapping table).
  const std::vector<std::pair<std::string, std::vector<std::string>>> table = {
      {"pelvis", {"joint-pelvis"}},
      {"left_hip", {"joint-l-upper-leg"}},
      {"right_hip", {"joint-r-upper-leg"}},
      {"spine1", {"joint-spine-3"}},
      {"left_knee", {"joint-l-knee"}},
      {"right_knee", {"joint-r-knee"}},
      {"spine2", {"joint-spine-2"}},
      {"left_ankle", {"joint-l-ankle"}},
      {"right_ankle", {"joint-r-ankle"}},
      {"spine3", {"joint-spine-1"}},
      {"left_foot", {"joint-l-toe-1-1", "joint-l-toe-2-1", "joint-l-toe-3-1", "joint-l-toe-4-1", "joint-l-toe-5-1"}},
      {"right_foot", {"joint-r-toe-1-1", "joint-r-toe-2-1", "joint-r-toe-3-1", "joint-r-toe-4-1", "joint-r-toe-5-1"}},
      {"neck", {"joint-neck"}},
      {"left_collar", {"joint-l-clavicle"}},
      {"right_collar", {"joint-r-clavicle"}},
      {"head", {"joint-head"}},
      {"left_shoulder", {"joint-l-shoulder"}},
      {"right_shoulder", {"joint-r-shoulder"}},
      {"left_elbow", {"joint-l-elbow"}},
      {"right_elbow", {"joint-r-elbow"}},
      {"left_wrist", {"joint-l-hand"}},
      {"right_wrist", {"joint-r-hand"}},
      {"left_hand", {"joint-l-finger-2-1", "joint-l-finger-3-1", "joint-l-finger-4-1", "joint-l-finger-5-1"}},
      {"right_hand", {"joint-r-finger-2-1", "joint-r-finger-3-1", "joint-r-finger-4-1", "joint-r-finger-5-1"}}};
  const Points J = regress_joints(*model_, model_->v_template);
  ASSERT_EQ(J.rows(), 24);
  for (int j = 0; j < 24; ++j) {
    ASSERT_EQ(model_->joint_names[j], table[j].first);
    Vec3 c = Vec3::Zero();
    for (const auto& g : table[j].second) c += group_centre(g);
    c /= double(table[j].second.size());
    EXPECT_LT((J.row(j).transpose() - c).norm(), 0.01) << table[j].first << " at " << J.row(j) << ", groups' centre "
                                                      << c.transpose();
  }
  // The regressor is over surface vertices, non-negative, rows summing to 1.
  for (int j = 0; j < 24; ++j) {
    double s = 0;
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(model_->J_regressor, j); it; ++it) {
      EXPECT_GE(it.value(), 0.0);
      s += it.value();
    }
    EXPECT_NEAR(s, 1.0, 1e-9) << j;
  }
  // SMPL's tree.
  const std::vector<int> parents = {-1, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 9, 9, 12, 13, 14, 16, 17, 18, 19, 20, 21};
  EXPECT_EQ(model_->parents, parents);
}

TEST_F(MakeHumanModel, WeightsSumToOneAndAggregateTheMakeHumanBones) {
  const MatXr& W = model_->weights;
  ASSERT_EQ(W.rows(), kBodyVertices);
  EXPECT_GE(W.minCoeff(), 0.0);
  EXPECT_LT((W.rowwise().sum().array() - 1.0).abs().maxCoeff(), 1e-12);
  // Against default_weights.mhw read here: a joint's weight is its bones' share of the vertex's
  // total MakeHuman weight.
  const auto bones = read_bone_weights(folder_ + "/default_weights.mhw");
  ASSERT_GT(bones.size(), 100u);
  VecX total = VecX::Zero(kBodyVertices);
  for (const auto& [name, pairs] : bones)
    for (auto [v, w] : pairs)
      if (v < kBodyVertices) total[v] += w;
  const std::vector<std::pair<std::string, std::vector<std::string>>> checks = {
      {"left_knee", {"lowerleg01.L", "lowerleg02.L"}},
      {"right_elbow", {"lowerarm01.R", "lowerarm02.R"}},
      {"spine1", {"spine03"}},
      {"left_shoulder", {"upperarm01.L", "upperarm02.L"}}};
  for (const auto& [joint, names] : checks) {
    const int j = int(std::find(model_->joint_names.begin(), model_->joint_names.end(), joint) -
                      model_->joint_names.begin());
    VecX expect = VecX::Zero(kBodyVertices);
    for (const auto& n : names) {
      ASSERT_TRUE(bones.count(n)) << n;
      for (auto [v, w] : bones.at(n))
        if (v < kBodyVertices) expect[v] += w;
    }
    expect = expect.cwiseQuotient(total);
    EXPECT_LT((W.col(j) - expect).cwiseAbs().maxCoeff(), 1e-12) << joint;
    EXPECT_GT(expect.sum(), 100.0) << joint << " covers too few vertices to be a check";
  }
}

TEST_F(MakeHumanModel, ZeroShapeGivesTheBaseMeshInMetres) {
  const Points v0 = shape_vertices(*model_, VecX::Zero(model_->num_betas()));
  EXPECT_LT((v0 - base_metres()).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_FALSE(model_->has_pose_blend_shapes());
}

TEST_F(MakeHumanModel, ShapeDirectionsReachTheMakeHumanTargetsAndHaveMeanings) {
  ASSERT_EQ(model_->num_betas(), 10);
  ASSERT_EQ(model_->shape_meanings.size(), 10u);
  for (const auto& m : model_->shape_meanings) EXPECT_GT(m.size(), 10u);
  const Points base = base_metres();
  // β = ±3 on a direction and its companions is the target itself (documented in the converter).
  struct Case {
    std::string target;
    std::vector<double> betas;
  };
  const std::vector<Case> cases = {
      {"universal-female-young-averagemuscle-maxweight", {3, 0, 0, 3, 0, 3, 0, 3, 0, 0}},
      {"universal-male-young-averagemuscle-minweight", {-3, 0, 0, 3, 0, 3, 0, -3, 0, 0}},
      {"universal-male-young-maxmuscle-averageweight", {0, 3, 0, 0, -3, 0, 3, 0, -3, 0}},
      {"height-female-young-averagemuscle-averageweight-maxheight", {0, 0, 3, 0, 0, 0, 0, 0, 0, 3}},
      {"height-male-young-averagemuscle-averageweight-minheight", {0, 0, -3, 0, 0, 0, 0, 0, 0, 3}}};
  for (const Case& c : cases) {
    const Points target = base + 0.1 * read_target(folder_ + "/targets/" + c.target + ".target", kBodyVertices);
    const Points shaped = shape_vertices(*model_, Eigen::Map<const VecX>(c.betas.data(), 10));
    EXPECT_LT((shaped - target).cwiseAbs().maxCoeff(), 1e-9) << c.target;
    EXPECT_GT((target - base).cwiseAbs().maxCoeff(), 1e-3) << c.target << " is empty";
  }
}

// Needs no MakeHuman data: the hole filler closes a cube with a missing side exactly, and a
// folder without base.obj gives one error line, exit 1 and no output file.
TEST(MakeHumanConverter, FillsHolesAndRejectsAMissingFolderWithOneLine) {
  std::string log;
  const std::string tool = "/usr/bin/python3 " + test::source_dir() + "/data_tools/makehuman_to_smpl.py";
  ASSERT_EQ(test::run_command(tool + " --self-test", &log), 0) << log;
  EXPECT_NE(log.find("self-test passed"), std::string::npos) << log;
  test::TempDir dir;
  const std::string out = dir.file("mh.h5");
  EXPECT_EQ(test::run_command(tool + " " + dir.file("nowhere") + " " + out, &log), 1) << log;
  EXPECT_NE(log.find("nowhere/base.obj: cannot read"), std::string::npos) << log;
  EXPECT_EQ(std::count(log.begin(), log.end(), '\n'), 1) << log;
  EXPECT_FALSE(std::filesystem::exists(out));
  EXPECT_FALSE(std::filesystem::exists(out + ".partial"));
}

}  // namespace
}  // namespace sflsh
