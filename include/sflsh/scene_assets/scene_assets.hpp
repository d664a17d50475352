#pragma once
// What a scene needs beyond its file, prepared before a session is built, so
// that the runtime libraries (sim, scene, teleop, viewer) link neither CGAL nor
// the precompute pipeline:
//   * every mesh shape (objects, tools, jaws) is read, checked closed and
//     manifold, and baked into a grid SDF with CGAL (meshing/mesh_sdf_bake.hpp),
//     or loaded from `cache_dir`/mesh_sdf when it was baked before;
//   * every `avatar: default` body is resolved to the built-in body's avatar,
//     precomputed on first use into `cache_dir`/avatars (precompute/cached_avatar.hpp).
// The sflsh commands call it; a program that builds a SceneSession from a
// scene with mesh shapes or `avatar: default` calls it first.
#include <string>

#include "sflsh/scene/scene_description.hpp"

namespace sflsh {

/// Prepares `scene` in place (ShapeDescription::baked_sdf, BodyDescription::avatar).
/// `cache_dir` "" bakes without a cache (and refuses `avatar: default`, which
/// needs one). Progress lines on stderr when `progress`. Throws one line naming
/// the scene location (e.g. "scene.yaml:12: objects[2].shape: rock.obj: ...").
void prepare_scene_assets(SceneDescription& scene, const std::string& cache_dir, bool progress = true);

}  // namespace sflsh
