#pragma once
// Triangle surface files. The format follows the extension:
//  - .obj  Wavefront OBJ, written directly; coordinates with the shortest
//          decimal that reads back to the same double (exact round trip);
//          per-vertex colours as the common "v x y z r g b" extension.
//  - .ply  binary little-endian PLY, written directly; float32 x y z and,
//          with colours, uchar red green blue.
//  - .glb / .gltf  glTF 2.0 through assimp (Assimp::Exporter "glb2"/"gltf2"),
//          with smooth vertex normals and COLOR_0 when colours are given.
// Units are whatever V is in (sflsh: metres, Y up). Writes are atomic: nothing
// is left at the target path when writing fails.
#include <cstddef>
#include <string>
#include <vector>

#include "sflsh/core/types.hpp"

namespace sflsh::io {

/// The extensions write_mesh understands (".obj", ".ply", ".glb", ".gltf").
const std::vector<std::string>& mesh_export_extensions();

/// Throws "<what>: unknown mesh format '<ext>'; supported: .obj, ..." unless
/// `path` ends in one of mesh_export_extensions() (case-insensitive).
void require_mesh_export_extension(const std::string& path, const std::string& what);

/// Writes the surface (V: #V by 3, F: #F by 3 0-based counter-clockwise) to
/// `path`, format from the extension. `colors` is empty or #V by 3 RGB in
/// [0, 1] (clamped). Throws sflsh::Error naming the path on an unknown
/// extension (listing the supported ones), bad indices, NaN or I/O failure.
void write_mesh(const std::string& path, const Points& V, const Triangles& F, const Points& colors = Points());

/// A surface read from a file.
struct ImportedMesh {
  Points vertices;   ///< #V by 3, in the file's units
  Triangles faces;   ///< #F by 3, 0-based
  Points colors;     ///< #V by 3 RGB in [0, 1], or empty when the file has none
};

/// Reads any surface format assimp imports (OBJ, PLY, glTF/glb, STL, FBX, ...)
/// with identical vertices joined and polygons triangulated; all meshes of the
/// file are concatenated with their node transforms applied. Vertex order is
/// assimp's, not necessarily the file's. Throws naming the path on failure or
/// when the file holds no triangles.
ImportedMesh read_mesh(const std::string& path);
/// The same for a file's `size` bytes in memory; `format` is assimp's hint,
/// the file extension without dot ("obj", "stl", "ply"), and `name` stands for
/// the file in errors.
ImportedMesh read_mesh_from_memory(const void* data, std::size_t size, const std::string& format,
                                   const std::string& name);

}  // namespace sflsh::io
