#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>

#include <assimp/Importer.hpp>
#include <assimp/anim.h>
#include <assimp/scene.h>

#include "sflsh/core/error.hpp"
#include "sflsh/io/gltf_animation.hpp"
#include "io/glb_dump.hpp"
#include "test_support.hpp"

namespace sflsh::io {
namespace {

namespace fs = std::filesystem;

/// A tetrahedron moving and deforming over `n` frames.
std::vector<Points> moving_tet(int n, Triangles& F) {
  F.resize(4, 3);
  F << 0, 2, 1, 0, 1, 3, 1, 2, 3, 0, 3, 2;
  std::vector<Points> frames;
  for (int k = 0; k < n; ++k) {
    Points P(4, 3);
    P << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1;
    P.col(1).array() += 0.1 * k;  // rises
    P(3, 2) += 0.05 * k;          // apex stretches
    frames.push_back(P);
  }
  return frames;
}

TEST(GltfAnimation, MorphTargetsReadBackThroughAssimp) {
  test::TempDir dir;
  Triangles F;
  const auto frames = moving_tet(4, F);
  write_animated_glb(dir.file("a.glb"), frames, F, 30.0);

  // GLB header: magic, version 2, total length = file size.
  std::ifstream is(dir.file("a.glb"), std::ios::binary);
  std::uint32_t header[3];
  is.read(reinterpret_cast<char*>(header), 12);
  EXPECT_EQ(header[0], 0x46546C67u);
  EXPECT_EQ(header[1], 2u);
  EXPECT_EQ(header[2], fs::file_size(dir.file("a.glb")));

  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(dir.file("a.glb"), 0);
  ASSERT_NE(scene, nullptr) << importer.GetErrorString();
  ASSERT_EQ(scene->mNumMeshes, 1u);
  const aiMesh* mesh = scene->mMeshes[0];
  ASSERT_EQ(mesh->mNumFaces, 4u);
  ASSERT_EQ(mesh->mNumAnimMeshes, 3u) << "one morph target per frame after the first";
  // Whatever vertex order assimp uses, base + target k-1 must be frame k.
  for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
    const aiVector3D& b = mesh->mVertices[v];
    int match = -1;
    for (int i = 0; i < 4; ++i)
      if ((Vec3(b.x, b.y, b.z) - frames[0].row(i).transpose()).norm() < 1e-6) match = i;
    ASSERT_GE(match, 0);
    for (unsigned t = 0; t < 3; ++t) {
      const aiVector3D& p = mesh->mAnimMeshes[t]->mVertices[v];
      EXPECT_LT((Vec3(p.x, p.y, p.z) - frames[t + 1].row(match).transpose()).norm(), 1e-5) << "target " << t;
    }
  }
  ASSERT_EQ(scene->mNumAnimations, 1u);
  const aiAnimation* anim = scene->mAnimations[0];
  ASSERT_EQ(anim->mNumMorphMeshChannels, 1u);
  EXPECT_EQ(anim->mMorphMeshChannels[0]->mNumKeys, 4u);
}

TEST(GltfAnimation, SingleFrameAndBadInput) {
  test::TempDir dir;
  Triangles F;
  auto frames = moving_tet(1, F);
  write_animated_glb(dir.file("one.glb"), frames, F, 30.0);
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(dir.file("one.glb"), 0);
  ASSERT_NE(scene, nullptr) << importer.GetErrorString();
  EXPECT_EQ(scene->mMeshes[0]->mNumAnimMeshes, 0u);

  frames = moving_tet(3, F);
  frames[2].resize(3, 3);
  EXPECT_THROW(write_animated_glb(dir.file("bad.glb"), frames, F, 30.0), Error);
  EXPECT_THROW(write_animated_glb(dir.file("bad.gltf"), moving_tet(2, F), F, 30.0), Error);
  EXPECT_THROW(write_animated_glb(dir.file("bad.glb"), moving_tet(2, F), F, 0.0), Error);
  EXPECT_FALSE(fs::exists(dir.file("bad.glb")));
}

TEST(GltfAnimation, RigidNodesMoveByTranslationAndRotationChannels) {
  test::TempDir dir;
  Triangles F;
  const auto frames = moving_tet(4, F);
  Triangles tri(1, 3);
  tri << 0, 1, 2;
  GltfRigidNode ball{"ball \"one\"", frames[0], F, {}, {}};
  GltfRigidNode floor{"floor", Points::Identity(3, 3), tri, {}, {}, Vec3(0.5, 0.5, 0.5), true};
  for (int k = 0; k < 4; ++k) {
    ball.translations.push_back(Vec3(0.5 * k, 1.0, -0.25 * k));
    // A turn by 0.7·k about +Z; odd frames given as −q (the same rotation).
    const Eigen::Quaterniond q(Eigen::AngleAxisd(0.7 * k, Vec3::UnitZ()));
    ball.rotations.push_back(k % 2 ? Eigen::Quaterniond(-q.coeffs()) : q);
    floor.translations.push_back(Vec3(0, -0.1, 0));
    floor.rotations.push_back(Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Vec3::UnitX())));
  }
  write_animated_glb(dir.file("s.glb"), frames, F, 25.0, Points(), {ball, floor});

  const test::GlbDump d = test::dump_glb(dir.file("s.glb"));
  ASSERT_EQ(d.nodes.size(), 3u);
  EXPECT_EQ(d.scene_nodes, (std::vector<int>{0, 1, 2}));
  EXPECT_EQ(d.nodes[0].name, "body");
  EXPECT_EQ(d.nodes[1].name, "ball \"one\"");
  EXPECT_EQ(d.nodes[2].name, "floor");
  EXPECT_EQ(d.mesh_vertices, (std::vector<int>{4, 4, 3}));
  EXPECT_EQ(d.mesh_material, (std::vector<int>{0, 1, 2}));
  EXPECT_EQ(d.material_double_sided, (std::vector<bool>{false, false, true}));
  EXPECT_EQ(d.material_color[1], (std::vector<double>{0.6, 0.6, 0.6, 1}));
  // Skin weights, the ball's translation and rotation; nothing for the still floor.
  ASSERT_EQ(d.channels.size(), 3u);
  EXPECT_NE(d.channel(0, "weights"), nullptr);
  const auto* t = d.channel(1, "translation");
  const auto* r = d.channel(1, "rotation");
  ASSERT_TRUE(t && r);
  EXPECT_EQ(d.channel(2, "translation"), nullptr);
  EXPECT_EQ(r->interpolation, "LINEAR");
  ASSERT_EQ(t->values.size(), 4u);
  ASSERT_EQ(r->values.size(), 4u);
  for (int k = 0; k < 4; ++k) {
    EXPECT_NEAR(t->times[size_t(k)], k / 25.0, 1e-7);
    const std::vector<double> tk = {0.5 * k, 1.0, -0.25 * k};
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(t->values[size_t(k)][size_t(c)], tk[size_t(c)], 1e-6) << k;
    // (x, y, z, w) = (0, 0, sin(0.35 k), cos(0.35 k)): all keys on one
    // hemisphere (cos > 0 here), whatever sign the input had.
    const std::vector<double> rk = {0, 0, std::sin(0.35 * k), std::cos(0.35 * k)};
    for (int c = 0; c < 4; ++c) EXPECT_NEAR(r->values[size_t(k)][size_t(c)], rk[size_t(c)], 1e-6) << k;
  }
  // The still floor's pose sits on its node: a turn by 0.3 about +X, lowered 0.1.
  ASSERT_EQ(d.nodes[2].translation.size(), 3u);
  EXPECT_NEAR(d.nodes[2].translation[1], -0.1, 1e-9);
  ASSERT_EQ(d.nodes[2].rotation.size(), 4u);
  EXPECT_NEAR(d.nodes[2].rotation[0], std::sin(0.15), 1e-8);
  EXPECT_NEAR(d.nodes[2].rotation[3], std::cos(0.15), 1e-8);

  // Assimp (what Blender-like importers use) reads the scene too.
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(dir.file("s.glb"), 0);
  ASSERT_NE(scene, nullptr) << importer.GetErrorString();
  EXPECT_EQ(scene->mNumMeshes, 3u);

  // A pose missing, or a scaled quaternion, is refused.
  floor.rotations.pop_back();
  test::expect_error([&] { write_animated_glb(dir.file("bad.glb"), frames, F, 25.0, Points(), {floor}); },
                     {"bad.glb", "'floor'", "3 rotations for 4 frames"});
  ball.rotations[2].coeffs() *= 1.01;
  test::expect_error([&] { write_animated_glb(dir.file("bad.glb"), frames, F, 25.0, Points(), {ball}); },
                     {"'ball", "rotation 2", "unit quaternion"});
  EXPECT_FALSE(fs::exists(dir.file("bad.glb")));
}

}  // namespace
}  // namespace sflsh::io
