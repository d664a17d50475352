#pragma once
// Skeletal animations of FBX, DAE (Collada), glTF and other formats assimp
// reads (and BVH, as a cross-check of the own parser): the node tree becomes
// the source skeleton, the first animation's node channels its frames.
#include <string>

#include "sflsh/motion/skeleton_motion.hpp"

namespace sflsh {

/// Reads the first animation of `path` through assimp. Frames are the keys of
/// the channel with the most rotation keys (assumed evenly spaced; fps =
/// ticks-per-second / key spacing); other channels are interpolated at those
/// times (slerp / linear), nodes without a channel keep their rest transform.
/// Throws naming the file when assimp cannot read it or it holds no animation.
SkeletonMotion read_assimp_motion(const std::string& path);

}  // namespace sflsh
