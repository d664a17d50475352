#include "scene_avatars.hpp"

#include <iostream>

#include "sflsh/body/body_model_io.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/precompute/cached_avatar.hpp"

namespace sflsh::cli {

void resolve_default_avatars(SceneDescription& scene, const std::string& cache_dir) {
  bool any = false;
  for (const BodyDescription& b : scene.bodies) any = any || (b.default_avatar && b.avatar == kDefaultAvatar);
  if (!any) return;
  const BodyModel model = load_body_model("procedural");
  PrecomputeOptions o;
  o.cache_dir = cache_dir;
  for (BodyDescription& b : scene.bodies) {
    if (!b.default_avatar || b.avatar != kDefaultAvatar) continue;
    std::cerr << "bodies '" << b.name << "': avatar: default" << (b.betas.size() ? " (betas given)" : "")
              << ": from the cache, or precomputed into it on first use (minutes, once)\n";
    try {
      const CachedAvatar c = cached_avatar(model, b.betas, o);
      std::cerr << "bodies '" << b.name << "': " << (c.built ? "built " : "cached ") << c.path << "\n";
      b.avatar = c.path;
    } catch (const Error& e) {
      fail(scene.path, ": bodies '", b.name, "': avatar: default: ", e.what());
    }
  }
}

}  // namespace sflsh::cli
