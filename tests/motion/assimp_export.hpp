#pragma once
// Test helper: writes a source skeleton's animation as a skinned, animated
// scene with assimp's own exporter (Assimp::Exporter), so that the FBX and
// glTF paths of the motion loader are tested on files no sflsh code wrote.
//
// The scene: a root node "Scene" holding the joint tree (local rest transform
// T(rest_translation) R(rest_rotation) per joint) and a node "skin" with one
// mesh: one small triangle per joint at the joint's rest position, weighted
// 1 to that joint's bone (offset matrix = inverse rest world transform), so
// every joint is a bone of a skinned mesh. One animation: per animated joint
// a channel with one rotation and one position key per frame.
//
// Key times are in seconds (mTicksPerSecond = 1): Debian's assimp 5.2.5 FBX
// exporter writes key times in ticks as if they were seconds (a clip with
// 10 ticks/s came back 10x slower from FBX; glTF2 converts correctly).
#include <assimp/Exporter.hpp>
#include <assimp/scene.h>

#include <memory>
#include <string>
#include <vector>

#include "sflsh/core/error.hpp"
#include "sflsh/motion/skeleton_motion.hpp"

namespace sflsh::test {

inline aiMatrix4x4 to_ai_matrix(const Eigen::Quaterniond& r, const Vec3& t) {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.topLeftCorner<3, 3>() = r.toRotationMatrix();
  m.topRightCorner<3, 1>() = t;
  return aiMatrix4x4(float(m(0, 0)), float(m(0, 1)), float(m(0, 2)), float(m(0, 3)), float(m(1, 0)), float(m(1, 1)),
                     float(m(1, 2)), float(m(1, 3)), float(m(2, 0)), float(m(2, 1)), float(m(2, 2)), float(m(2, 3)),
                     0.f, 0.f, 0.f, 1.f);
}

/// The skinned, animated scene of `motion` (see the file comment). The caller
/// owns the result (aiScene's destructor frees every part).
inline std::unique_ptr<aiScene> skinned_scene(const SkeletonMotion& motion) {
  const int n = motion.num_joints();
  auto scene = std::make_unique<aiScene>();
  // Joint nodes, parents before children (SkeletonMotion's order).
  std::vector<aiNode*> node(n);
  std::vector<std::vector<aiNode*>> children(n);
  auto* root = new aiNode("Scene");
  scene->mRootNode = root;
  std::vector<aiNode*> root_children;
  for (int j = 0; j < n; ++j) {
    node[j] = new aiNode(motion.names[j]);
    node[j]->mTransformation = to_ai_matrix(motion.rest_rotations[j], motion.rest_translations[j]);
    const int p = motion.parents[j];
    node[j]->mParent = p < 0 ? root : node[p];
    (p < 0 ? root_children : children[p]).push_back(node[j]);
  }
  auto* skin = new aiNode("skin");
  skin->mParent = root;
  skin->mNumMeshes = 1;
  skin->mMeshes = new unsigned[1]{0};
  root_children.push_back(skin);
  auto attach = [](aiNode* parent, const std::vector<aiNode*>& kids) {
    parent->mNumChildren = unsigned(kids.size());
    parent->mChildren = new aiNode*[kids.size()];
    for (size_t i = 0; i < kids.size(); ++i) parent->mChildren[i] = kids[i];
  };
  attach(root, root_children);
  for (int j = 0; j < n; ++j)
    if (!children[j].empty()) attach(node[j], children[j]);

  // The skin: one triangle per joint at its rest position, bound to it.
  std::vector<Eigen::Quaterniond> rest_r;
  std::vector<Vec3> rest_p;
  skeleton_world_pose(motion, -1, &rest_r, &rest_p);
  auto* mesh = new aiMesh;
  mesh->mName = "skin";
  mesh->mPrimitiveTypes = aiPrimitiveType_TRIANGLE;
  mesh->mMaterialIndex = 0;
  mesh->mNumVertices = unsigned(3 * n);
  mesh->mVertices = new aiVector3D[3 * n];
  mesh->mNumFaces = unsigned(n);
  mesh->mFaces = new aiFace[n];
  mesh->mNumBones = unsigned(n);
  mesh->mBones = new aiBone*[n];
  for (int j = 0; j < n; ++j) {
    for (int k = 0; k < 3; ++k) {
      const Vec3 v = rest_p[j] + Vec3(k == 1 ? 1.0 : 0.0, k == 2 ? 1.0 : 0.0, 0.0);
      mesh->mVertices[3 * j + k] = aiVector3D(float(v.x()), float(v.y()), float(v.z()));
    }
    mesh->mFaces[j].mNumIndices = 3;
    mesh->mFaces[j].mIndices = new unsigned[3]{unsigned(3 * j), unsigned(3 * j + 1), unsigned(3 * j + 2)};
    auto* bone = new aiBone;
    bone->mName = motion.names[j];
    bone->mNumWeights = 3;
    bone->mWeights = new aiVertexWeight[3];
    for (int k = 0; k < 3; ++k) bone->mWeights[k] = aiVertexWeight(unsigned(3 * j + k), 1.f);
    bone->mOffsetMatrix = to_ai_matrix(rest_r[j], rest_p[j]).Inverse();
    mesh->mBones[j] = bone;
  }
  scene->mNumMeshes = 1;
  scene->mMeshes = new aiMesh*[1]{mesh};
  scene->mNumMaterials = 1;
  scene->mMaterials = new aiMaterial*[1]{new aiMaterial};

  // The animation: rotation and position keys at f / fps seconds.
  auto* anim = new aiAnimation;
  anim->mName = "motion";
  anim->mTicksPerSecond = 1.0;
  anim->mDuration = (motion.num_frames - 1) / motion.fps;
  std::vector<aiNodeAnim*> channels;
  for (int j = 0; j < n; ++j) {
    if (!motion.animated[j]) continue;
    auto* ch = new aiNodeAnim;
    ch->mNodeName = motion.names[j];
    const unsigned K = unsigned(motion.num_frames);
    ch->mNumRotationKeys = K;
    ch->mRotationKeys = new aiQuatKey[K];
    ch->mNumPositionKeys = K;
    ch->mPositionKeys = new aiVectorKey[K];
    for (unsigned f = 0; f < K; ++f) {
      const size_t k = size_t(f) * n + j;
      const double t = f / motion.fps;
      const Eigen::Quaterniond& q = motion.rotations[k];
      ch->mRotationKeys[f] = aiQuatKey(t, aiQuaternion(float(q.w()), float(q.x()), float(q.y()), float(q.z())));
      const Vec3& p = motion.translations[k];
      ch->mPositionKeys[f] = aiVectorKey(t, aiVector3D(float(p.x()), float(p.y()), float(p.z())));
    }
    channels.push_back(ch);
  }
  anim->mNumChannels = unsigned(channels.size());
  anim->mChannels = new aiNodeAnim*[channels.size()];
  for (size_t c = 0; c < channels.size(); ++c) anim->mChannels[c] = channels[c];
  scene->mNumAnimations = 1;
  scene->mAnimations = new aiAnimation*[1]{anim};
  return scene;
}

/// Writes `scene` to `path` with assimp's exporter `format_id` ("glb2",
/// "gltf2", "fbx", "fbxa"); throws naming the format on failure.
inline void export_scene(const aiScene& scene, const std::string& format_id, const std::string& path) {
  Assimp::Exporter exporter;
  require(exporter.Export(&scene, format_id, path) == AI_SUCCESS, path, ": assimp's '", format_id,
          "' exporter failed: ", exporter.GetErrorString());
}

}  // namespace sflsh::test
