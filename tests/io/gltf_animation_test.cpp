#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>

#include <assimp/Importer.hpp>
#include <assimp/anim.h>
#include <assimp/scene.h>

#include "sflsh/core/error.hpp"
#include "sflsh/io/gltf_animation.hpp"
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

}  // namespace
}  // namespace sflsh::io
