#pragma once
// Avatars built on first use and kept in the cache: what a scene's
// `avatar: default` (optionally with `betas`) runs on, so that example scenes
// run as written, without a precompute step first.
#include <string>

#include "sflsh/body/body_model.hpp"
#include "sflsh/precompute/precompute.hpp"

namespace sflsh {

struct CachedAvatar {
  std::string path;    ///< the avatar file in the cache
  bool built = false;  ///< built by this call (else found in the cache)
};

/// The avatar of `model` at shape `betas` (padded with zeros to the model's
/// count) with `options`, from `options.cache_dir`/avatars/avatar-<key>.h5
/// (key: batch_precompute.hpp's avatar_content_key, so any option that changes
/// the avatar gives another file); built there on first use (template stage
/// from its cache), written under a name unique to this process and renamed,
/// so concurrent users never see a partial file. Throws naming the value for
/// non-finite betas, more betas than the model has, or no cache folder.
CachedAvatar cached_avatar(const BodyModel& model, const VecX& betas, const PrecomputeOptions& options);

}  // namespace sflsh
