#include "sflsh/scene_assets/scene_assets.hpp"

#include <iostream>

#include "sflsh/body/body_model_io.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/geometry/grid_sdf.hpp"
#include "sflsh/meshing/mesh_sdf_bake.hpp"
#include "sflsh/precompute/cached_avatar.hpp"

namespace sflsh {
namespace {

void bake(ShapeDescription& s, const std::string& what, const std::string& cache_dir) {
  if (s.type != ShapeType::Mesh || s.baked_sdf) return;
  const std::string where = s.location.empty() ? what : s.location;
  MeshSdfBakeOptions bo;
  bo.voxel_size = s.voxel_size;
  bo.padding = s.padding;
  bo.band = s.band;
  MeshSdfBakeReport rep;
  try {
    s.baked_sdf = std::make_shared<const geometry::GridSdf>(
        load_or_bake_mesh_sdf(s.mesh_file, s.mesh_scale, bo, cache_dir, &rep));
  } catch (const Error& e) {
    fail(where, ": ", e.what());
  }
  s.bake_report = rep.describe();  // printed by the session that uses it
}

void resolve_default_avatars(SceneDescription& scene, const std::string& cache_dir, bool progress) {
  bool any = false;
  for (const BodyDescription& b : scene.bodies) any = any || (b.default_avatar && b.avatar == kDefaultAvatar);
  if (!any) return;
  const std::string where = scene.path.empty() ? "scene" : scene.path;
  require(!cache_dir.empty(), where, ": avatar: default needs a cache folder (it is precomputed once into it)");
  const BodyModel model = load_body_model("procedural");
  PrecomputeOptions o;
  o.cache_dir = cache_dir;
  o.bbw.show_progress = progress;
  for (BodyDescription& b : scene.bodies) {
    if (!b.default_avatar || b.avatar != kDefaultAvatar) continue;
    if (progress)
      std::cerr << "bodies '" << b.name << "': avatar: default" << (b.betas.size() ? " (betas given)" : "")
                << ": from the cache, or precomputed into it on first use (minutes, once)\n";
    try {
      const CachedAvatar c = cached_avatar(model, b.betas, o);
      if (progress) std::cerr << "bodies '" << b.name << "': " << (c.built ? "built " : "cached ") << c.path << "\n";
      b.avatar = c.path;
    } catch (const Error& e) {
      fail(where, ": bodies '", b.name, "': avatar: default: ", e.what());
    }
  }
}

}  // namespace

void prepare_scene_assets(SceneDescription& scene, const std::string& cache_dir, bool progress) {
  for (RigidObjectDescription& o : scene.objects) bake(o.shape, "objects '" + o.name + "'", cache_dir);
  for (ToolDescription& t : scene.tools) {
    if (t.has_shape) bake(t.shape, "tools '" + t.name + "'", cache_dir);
    for (size_t j = 0; j < t.jaws.size(); ++j)
      bake(t.jaws[j].shape, "tools '" + t.name + "' jaw " + std::to_string(j), cache_dir);
  }
  resolve_default_avatars(scene, cache_dir, progress);
}

}  // namespace sflsh
