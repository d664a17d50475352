#include "sflsh/motion/assimp_motion.hpp"

#include <assimp/config.h>
#include <assimp/scene.h>

#include <algorithm>
#include <assimp/Importer.hpp>
#include <cmath>
#include <map>

#include "sflsh/core/error.hpp"

namespace sflsh {
namespace {

Eigen::Quaterniond to_eigen(const aiQuaternion& q) { return Eigen::Quaterniond(q.w, q.x, q.y, q.z).normalized(); }
Vec3 to_eigen(const aiVector3D& v) { return Vec3(v.x, v.y, v.z); }

// Index of the last key with time <= t (keys sorted by time), and the blend
// factor towards the next one.
template <class Key>
std::pair<unsigned, double> bracket(const Key* keys, unsigned n, double t) {
  if (n == 0 || t <= keys[0].mTime) return {0, 0.0};
  const Key* it = std::upper_bound(keys, keys + n, t, [](double v, const Key& k) { return v < k.mTime; });
  const unsigned i = unsigned(it - keys) - 1;
  if (i + 1 >= n) return {n - 1, 0.0};
  const double span = keys[i + 1].mTime - keys[i].mTime;
  return {i, span > 0 ? (t - keys[i].mTime) / span : 0.0};
}

}  // namespace

SkeletonMotion read_assimp_motion(const std::string& path) {
  Assimp::Importer importer;
  // Without this, FBX pivots become extra "$AssimpFbx$" nodes between joints.
  importer.SetPropertyBool(AI_CONFIG_IMPORT_FBX_PRESERVE_PIVOTS, false);
  const aiScene* scene = importer.ReadFile(path, 0);
  require(scene != nullptr && scene->mRootNode != nullptr, path, ": assimp cannot read the file: ",
          importer.GetErrorString());
  require(scene->mNumAnimations > 0, path, ": the file holds no animation (assimp found ", scene->mNumMeshes,
          " meshes, 0 animations)");
  const aiAnimation* anim = scene->mAnimations[0];
  const double tps = anim->mTicksPerSecond > 0 ? anim->mTicksPerSecond : 25.0;

  std::map<std::string, const aiNodeAnim*> channel_of;
  const aiNodeAnim* longest = nullptr;
  for (unsigned c = 0; c < anim->mNumChannels; ++c) {
    const aiNodeAnim* ch = anim->mChannels[c];
    channel_of[ch->mNodeName.C_Str()] = ch;
    if (!longest || ch->mNumRotationKeys > longest->mNumRotationKeys) longest = ch;
  }
  require(longest != nullptr && longest->mNumRotationKeys > 0, path, ": the animation '", anim->mName.C_Str(),
          "' has no rotation keys");

  SkeletonMotion m;
  m.source = path;
  // Flatten the node tree depth first (parents before children).
  std::vector<const aiNode*> nodes;
  std::vector<std::pair<const aiNode*, int>> stack = {{scene->mRootNode, -1}};
  while (!stack.empty()) {
    auto [node, parent] = stack.back();
    stack.pop_back();
    const int id = int(nodes.size());
    nodes.push_back(node);
    m.names.emplace_back(node->mName.C_Str());
    m.parents.push_back(parent);
    aiVector3D s, p;
    aiQuaternion r;
    node->mTransformation.Decompose(s, r, p);
    m.rest_rotations.push_back(to_eigen(r));
    m.rest_translations.push_back(to_eigen(p));
    m.scales.push_back((std::abs(s.x) + std::abs(s.y) + std::abs(s.z)) / 3.0);
    m.animated.push_back(channel_of.count(m.names.back()) > 0);
    for (int c = int(node->mNumChildren) - 1; c >= 0; --c) stack.emplace_back(node->mChildren[c], id);
  }

  const unsigned K = longest->mNumRotationKeys;
  const double t0 = longest->mRotationKeys[0].mTime;
  const double dt = K > 1 ? (longest->mRotationKeys[K - 1].mTime - t0) / (K - 1) : 1.0;
  require(dt > 0 && std::isfinite(dt), path, ": animation keys are not increasing in time");
  m.num_frames = int(K);
  m.fps = tps / dt;
  const int n = m.num_joints();
  m.rotations.resize(size_t(K) * n);
  m.translations.resize(size_t(K) * n);
  for (unsigned f = 0; f < K; ++f) {
    const double t = t0 + f * dt;
    for (int j = 0; j < n; ++j) {
      const size_t k = size_t(f) * n + j;
      m.rotations[k] = m.rest_rotations[j];
      m.translations[k] = m.rest_translations[j];
      const auto it = channel_of.find(m.names[j]);
      if (it == channel_of.end()) continue;
      const aiNodeAnim* ch = it->second;
      if (ch->mNumRotationKeys > 0) {
        const auto [i, a] = bracket(ch->mRotationKeys, ch->mNumRotationKeys, t);
        const auto q0 = to_eigen(ch->mRotationKeys[i].mValue);
        m.rotations[k] = a > 0 ? q0.slerp(a, to_eigen(ch->mRotationKeys[i + 1].mValue)) : q0;
      }
      if (ch->mNumPositionKeys > 0) {
        const auto [i, a] = bracket(ch->mPositionKeys, ch->mNumPositionKeys, t);
        const Vec3 p0 = to_eigen(ch->mPositionKeys[i].mValue);
        m.translations[k] = a > 0 ? Vec3((1 - a) * p0 + a * to_eigen(ch->mPositionKeys[i + 1].mValue)) : p0;
      }
    }
  }
  return m;
}

}  // namespace sflsh
