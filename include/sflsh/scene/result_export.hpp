#pragma once
// Outputs of a simulation that people open elsewhere (the HDF5 result stays
// canonical): PC2 point cache + rest mesh (Blender/Maya/Max), per-frame mesh
// sequences, and a PNG strip of frames coloured by soft displacement.
//
// Scenes with rigid objects (SimulationResult::objects): every output shows
// them, posed per frame, with the surfaces of object_display_meshes() (a
// plane becomes a finite square patch under the bodies).
#include <string>
#include <vector>

#include "sflsh/geometry/primitive_meshes.hpp"
#include "sflsh/scene/simulation_run.hpp"

namespace sflsh {

/// The objects' surfaces as the outputs draw them, each in its object's own
/// frame: ObjectTrack::vertices/faces, except for planes. A plane's track
/// holds any flat patch of it (its faces' area-weighted normal is the plane's
/// outward normal, its vertices' mean a point on it); it is redrawn as the
/// square patch of that plane (geometry::plane_patch_mesh, 2 triangles) centred
/// under the bodies' skin over all frames (in the plane's frame at each
/// frame's pose) with half size 1.2·R + 0.25 m, R = the largest distance of a
/// projected skin vertex from that centre. Throws naming the object if a
/// plane's patch has no normal.
std::vector<geometry::PrimitiveMesh> object_display_meshes(const SimulationResult& result);

/// By extension: ".pc2" writes the cache plus "<stem>_rest.obj" beside it (the
/// first frame's mesh, which the cache animates); ".glb" an animated glTF
/// (morph targets, plays in any glTF viewer); a pattern with a printf-style
/// frame field (e.g. "frames_%04d.obj", .ply, .glb) one mesh per frame.
/// With rigid objects: the .glb has one more node per object (own mesh, grey
/// material, translation/rotation channels; node 0 stays the skin); the
/// cache and the per-frame meshes hold the skin's vertices first, then each
/// object's posed display mesh in order, merged into one mesh. Returns a line
/// saying what was written (and that objects were merged).
std::string export_result(const SimulationResult& result, const std::string& path);

/// A strip of `num_frames` evenly spaced frames, skin coloured by the soft
/// displacement magnitude |u| in mm, with a colour bar. Rigid objects are
/// drawn posed per frame in neutral grey; the framing holds the bodies and
/// finite objects (up to half the bodies' extent beyond them), never a
/// plane's patch, and each panel clips what lies outside it. PNG.
void render_result(const SimulationResult& result, const std::string& path, int num_frames = 6);

}  // namespace sflsh
