#pragma once
// Animated surfaces as one glTF 2.0 binary (.glb) that viewers play back
// (Blender's glTF importer, three.js / Babylon viewers, Windows 3D Viewer).
//
// Assimp 5.2's glTF2 exporter writes node animations but not morph-weight
// animations, so this writer produces the file itself (glTF 2.0 spec §3.7.2.2
// morph targets, §3.11 animations): frame 0 is the base mesh, every later
// frame k is a morph target holding (positions_k − positions_0) and
// (normals_k − normals_0), and one animation drives the mesh weights with a
// one-hot keyframe per frame. LINEAR interpolation between keyframes then
// reproduces linear interpolation of vertex positions between frames.
// Size: about 24 bytes per vertex per frame (10k vertices, 300 frames: 72 MB).
//
// Rigid parts of a scene (objects) are separate nodes with their own
// mesh and material, moved by translation and rotation channels (§3.11; one
// LINEAR key per frame, rotations as unit quaternions x y z w, signs chosen
// so that consecutive keys are on the same hemisphere and slerp takes the
// short way). A node whose pose never changes gets no channels, only its
// node translation/rotation.
#include <string>
#include <vector>

#include "sflsh/core/types.hpp"

namespace sflsh::io {

/// A rigid part of the scene: its own mesh, moved by a pose per frame
/// (x_world = R·x + t).
struct GltfRigidNode {
  std::string name;
  Points vertices;                            ///< #N by 3, in the node's own frame (m)
  Triangles faces;                            ///< #M by 3, counter-clockwise from outside
  std::vector<Vec3> translations;             ///< t per frame (m), as many as the skin's frames
  std::vector<Eigen::Quaterniond> rotations;  ///< R per frame as a unit quaternion
  Vec3 color = Vec3(0.6, 0.6, 0.6);           ///< base colour, RGB in [0, 1] (default neutral grey)
  bool double_sided = false;                  ///< draw both sides (an open sheet, e.g. a floor patch)
};

/// Writes `frames` (each #V by 3, metres, same #V) with faces F (#F by 3) as
/// an animated .glb playing at `fps` frames per second, plus the `rigid`
/// nodes (node 0 is the skin, node 1 + i is rigid[i]). `colors` is empty or
/// #V by 3 RGB in [0, 1] (constant over time). Atomic; throws naming the path
/// on empty input, mismatched sizes (a rigid node needs one pose per frame),
/// NaN, a non-unit quaternion or a name not ending in .glb.
void write_animated_glb(const std::string& path, const std::vector<Points>& frames, const Triangles& F, double fps,
                        const Points& colors = Points(), const std::vector<GltfRigidNode>& rigid = {});

}  // namespace sflsh::io
