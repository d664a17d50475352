#pragma once
// `avatar: default` in a scene: the built-in body's avatar, from the cache or
// built there on first use (precompute/cached_avatar.hpp).
#include <string>

#include "sflsh/scene/scene_description.hpp"

namespace sflsh::cli {

/// Replaces every `avatar: default` body's avatar by the cached file of the
/// built-in body at its betas (default precompute settings), building it on
/// first use with progress on stderr. `cache_dir`: the template and avatar cache.
void resolve_default_avatars(SceneDescription& scene, const std::string& cache_dir);

}  // namespace sflsh::cli
