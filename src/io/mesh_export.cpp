#include "sflsh/io/mesh_export.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <random>
#include <string_view>

#include <assimp/Exporter.hpp>
#include <assimp/Importer.hpp>
#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include "sflsh/core/error.hpp"
#include "sflsh/io/atomic_output.hpp"
#include "sflsh/io/crash_isolation.hpp"
#include "sflsh/io/ply_structure.hpp"
#include "sflsh/io/surface_normals.hpp"

namespace sflsh::io {

namespace fs = std::filesystem;

namespace {

/// Default surface colour where no per-vertex colours are given (a light skin tone).
const Vec3 kSkinColor(0.87, 0.72, 0.62);

void validate(const std::string& path, const Points& V, const Triangles& F, const Points& colors) {
  require(V.allFinite(), path, ": vertex positions contain NaN or Inf");
  if (F.size() > 0)
    require(F.minCoeff() >= 0 && F.maxCoeff() < V.rows(), path, ": face indices must lie in [0, ", V.rows(),
            "), got [", F.minCoeff(), ", ", F.maxCoeff(), "]");
  require(colors.rows() == 0 || colors.rows() == V.rows(), path, ": colors has ", colors.rows(),
          " rows, expected 0 or #V = ", V.rows());
  require(colors.rows() == 0 || colors.allFinite(), path, ": colors contain NaN or Inf");
}

std::uint8_t to_byte(double c) { return std::uint8_t(std::lround(std::clamp(c, 0.0, 1.0) * 255.0)); }

/// Appends the shortest decimal that parses back to exactly `x`.
void append_number(std::string& out, double x) {
  char buf[32];
  auto res = std::to_chars(buf, buf + sizeof buf, x);
  out.append(buf, res.ptr);
}

void append_int(std::string& out, long x) {
  char buf[24];
  auto res = std::to_chars(buf, buf + sizeof buf, x);
  out.append(buf, res.ptr);
}

void write_bytes(const std::string& path, const std::string& temp, const std::string& data) {
  std::ofstream os(temp, std::ios::binary);
  require(bool(os), path, ": cannot open ", temp, " for writing");
  os.write(data.data(), std::streamsize(data.size()));
  os.close();
  require(bool(os), path, ": write failed (disk full?)");
}

void write_obj(const std::string& path, const std::string& temp, const Points& V, const Triangles& F,
               const Points& colors) {
  std::string s;
  s.reserve(size_t(V.rows()) * 64 + size_t(F.rows()) * 24 + 64);
  s += "# sflsh surface: ";
  append_int(s, long(V.rows()));
  s += " vertices, ";
  append_int(s, long(F.rows()));
  s += " triangles; units: metres, Y up\n";
  for (Eigen::Index v = 0; v < V.rows(); ++v) {
    s += "v ";
    for (int c = 0; c < 3; ++c) {
      append_number(s, V(v, c));
      s += c < 2 ? ' ' : (colors.rows() ? ' ' : '\n');
    }
    if (colors.rows()) {
      char buf[48];
      std::snprintf(buf, sizeof buf, "%.4f %.4f %.4f\n", std::clamp(colors(v, 0), 0.0, 1.0),
                    std::clamp(colors(v, 1), 0.0, 1.0), std::clamp(colors(v, 2), 0.0, 1.0));
      s += buf;
    }
  }
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    s += "f ";
    for (int c = 0; c < 3; ++c) {
      append_int(s, long(F(f, c)) + 1);  // OBJ indices are 1-based
      s += c < 2 ? ' ' : '\n';
    }
  }
  write_bytes(path, temp, s);
}

void put_u32(std::string& out, std::uint32_t x) {
  const char b[4] = {char(x & 0xff), char((x >> 8) & 0xff), char((x >> 16) & 0xff), char((x >> 24) & 0xff)};
  out.append(b, 4);
}
void put_f32(std::string& out, float x) {
  std::uint32_t u;
  std::memcpy(&u, &x, 4);
  put_u32(out, u);
}

void write_ply(const std::string& path, const std::string& temp, const Points& V, const Triangles& F,
               const Points& colors) {
  const bool has_colors = colors.rows() > 0;
  std::string s =
      "ply\nformat binary_little_endian 1.0\ncomment sflsh surface, units: metres, Y up\nelement vertex " +
      std::to_string(V.rows()) + "\nproperty float x\nproperty float y\nproperty float z\n";
  if (has_colors) s += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  s += "element face " + std::to_string(F.rows()) + "\nproperty list uchar int vertex_indices\nend_header\n";
  s.reserve(s.size() + size_t(V.rows()) * 15 + size_t(F.rows()) * 13);
  for (Eigen::Index v = 0; v < V.rows(); ++v) {
    for (int c = 0; c < 3; ++c) put_f32(s, float(V(v, c)));
    if (has_colors)
      for (int c = 0; c < 3; ++c) s.push_back(char(to_byte(colors(v, c))));
  }
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    s.push_back(char(3));
    for (int c = 0; c < 3; ++c) put_u32(s, std::uint32_t(F(f, c)));
  }
  write_bytes(path, temp, s);
}

/// An assimp scene with one mesh and one material; owns everything it points to.
std::unique_ptr<aiScene> make_scene(const Points& V, const Triangles& F, const Points& colors) {
  auto scene = std::make_unique<aiScene>();
  scene->mRootNode = new aiNode("sflsh_body");
  scene->mRootNode->mNumMeshes = 1;
  scene->mRootNode->mMeshes = new unsigned[1]{0};

  auto* material = new aiMaterial();
  const aiString name("skin");
  material->AddProperty(&name, AI_MATKEY_NAME);
  const Vec3 base = colors.rows() ? Vec3(1, 1, 1) : kSkinColor;  // glTF multiplies COLOR_0 by the base colour
  const aiColor4D rgba(float(base.x()), float(base.y()), float(base.z()), 1.f);
  material->AddProperty(&rgba, 1, AI_MATKEY_BASE_COLOR);
  material->AddProperty(&rgba, 1, AI_MATKEY_COLOR_DIFFUSE);
  const float roughness = 0.7f, metallic = 0.f;
  material->AddProperty(&roughness, 1, AI_MATKEY_ROUGHNESS_FACTOR);
  material->AddProperty(&metallic, 1, AI_MATKEY_METALLIC_FACTOR);
  scene->mNumMaterials = 1;
  scene->mMaterials = new aiMaterial*[1]{material};

  auto* mesh = new aiMesh();
  mesh->mName = aiString("body");
  mesh->mMaterialIndex = 0;
  mesh->mPrimitiveTypes = aiPrimitiveType_TRIANGLE;
  const unsigned nv = unsigned(V.rows()), nf = unsigned(F.rows());
  const Points N = vertex_normals(V, F);
  mesh->mNumVertices = nv;
  mesh->mVertices = new aiVector3D[nv];
  mesh->mNormals = new aiVector3D[nv];
  for (unsigned v = 0; v < nv; ++v) {
    mesh->mVertices[v] = aiVector3D(float(V(v, 0)), float(V(v, 1)), float(V(v, 2)));
    mesh->mNormals[v] = aiVector3D(float(N(v, 0)), float(N(v, 1)), float(N(v, 2)));
  }
  if (colors.rows()) {
    mesh->mColors[0] = new aiColor4D[nv];
    for (unsigned v = 0; v < nv; ++v)
      mesh->mColors[0][v] = aiColor4D(float(std::clamp(colors(v, 0), 0.0, 1.0)),
                                      float(std::clamp(colors(v, 1), 0.0, 1.0)),
                                      float(std::clamp(colors(v, 2), 0.0, 1.0)), 1.f);
  }
  mesh->mNumFaces = nf;
  mesh->mFaces = new aiFace[nf];
  for (unsigned f = 0; f < nf; ++f) {
    aiFace& face = mesh->mFaces[f];
    face.mNumIndices = 3;
    face.mIndices = new unsigned[3]{unsigned(F(f, 0)), unsigned(F(f, 1)), unsigned(F(f, 2))};
  }
  scene->mNumMeshes = 1;
  scene->mMeshes = new aiMesh*[1]{mesh};
  return scene;
}

/// glTF through assimp. The exporter names side files (.gltf's .bin buffer)
/// after the output file, so it writes into a private folder next to the
/// target, and the finished files are moved into place only on success.
void write_gltf(const std::string& path, const Points& V, const Triangles& F, const Points& colors, bool binary) {
  const fs::path target(path);
  const fs::path dir = target.parent_path().empty() ? fs::path(".") : target.parent_path();
  std::error_code ec;
  fs::create_directories(dir, ec);
  std::random_device rd;
  const fs::path work = dir / (".sflsh-export-" + std::to_string(rd()));
  fs::create_directory(work, ec);
  if (ec) fail(path, ": cannot create temporary folder ", work.string(), ": ", ec.message());
  struct Cleanup {
    fs::path p;
    ~Cleanup() {
      std::error_code e;
      fs::remove_all(p, e);
    }
  } cleanup{work};

  auto scene = make_scene(V, F, colors);
  Assimp::Exporter exporter;
  const fs::path staged = work / target.filename();
  if (exporter.Export(scene.get(), binary ? "glb2" : "gltf2", staged.string()) != aiReturn_SUCCESS)
    fail(path, ": assimp glTF export failed: ", exporter.GetErrorString());
  // Move the main file last so that it appears only when its side files exist.
  for (const auto& entry : fs::directory_iterator(work)) {
    if (entry.path().filename() == target.filename()) continue;
    fs::rename(entry.path(), dir / entry.path().filename(), ec);
    if (ec) fail(path, ": cannot move ", entry.path().string(), " into place: ", ec.message());
  }
  fs::rename(staged, target, ec);
  if (ec) fail(path, ": cannot move ", staged.string(), " into place: ", ec.message());
}

}  // namespace

const std::vector<std::string>& mesh_export_extensions() {
  static const std::vector<std::string> exts = {".obj", ".ply", ".glb", ".gltf"};
  return exts;
}

void require_mesh_export_extension(const std::string& path, const std::string& what) {
  const std::string ext = lower_extension(path);
  const auto& exts = mesh_export_extensions();
  if (std::find(exts.begin(), exts.end(), ext) != exts.end()) return;
  std::string list;
  for (const auto& e : exts) list += (list.empty() ? "" : ", ") + e;
  fail(what, ": unknown mesh format '", ext.empty() ? std::string("(no extension)") : ext, "'; supported: ", list);
}

void write_mesh(const std::string& path, const Points& V, const Triangles& F, const Points& colors) {
  require_mesh_export_extension(path, path);
  const std::string ext = lower_extension(path);
  validate(path, V, F, colors);
  if (ext == ".glb" || ext == ".gltf") {
    write_gltf(path, V, F, colors, ext == ".glb");
    return;
  }
  AtomicOutput out(path);
  if (ext == ".obj")
    write_obj(path, out.temp_path(), V, F, colors);
  else
    write_ply(path, out.temp_path(), V, F, colors);
  out.commit();
}

namespace {

// ValidateDataStructure first: the other steps index out of bounds on a damaged
// file (a face index past the vertex count; found by scripts/fuzz.sh). No
// aiProcess_Triangulate: on damaged faces it aborts the process on an internal
// assert (assimp 5.2.5, TriangulateProcess.cpp:238; found by scripts/fuzz.sh);
// polygons are split into fans below instead.
constexpr unsigned kImportSteps =
    aiProcess_ValidateDataStructure | aiProcess_JoinIdenticalVertices | aiProcess_PreTransformVertices;

/// Triangles of a face: a triangle as is, a polygon of n > 3 corners as the fan
/// (0, i, i + 1) — exact for the convex polygons mesh exporters write (quads);
/// points and lines carry no surface (0).
unsigned triangles_of(const aiFace& face) { return face.mNumIndices >= 3 ? face.mNumIndices - 2 : 0; }

// The triangles of every mesh of `scene` (`path` names the file in errors).
ImportedMesh imported_triangles(const aiScene* scene, const std::string& path) {
  ImportedMesh out;
  size_t nv = 0, nf = 0;
  bool any_colors = false;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    nv += scene->mMeshes[m]->mNumVertices;
    for (unsigned f = 0; f < scene->mMeshes[m]->mNumFaces; ++f) nf += triangles_of(scene->mMeshes[m]->mFaces[f]);
    any_colors |= scene->mMeshes[m]->HasVertexColors(0);
  }
  require(nf > 0, path, ": the file holds no triangles");
  out.vertices.resize(Eigen::Index(nv), 3);
  out.faces.resize(Eigen::Index(nf), 3);
  if (any_colors) out.colors = Points::Ones(Eigen::Index(nv), 3);
  Eigen::Index vbase = 0, fi = 0;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh* mesh = scene->mMeshes[m];
    for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
      const aiVector3D& p = mesh->mVertices[v];
      out.vertices.row(vbase + v) << p.x, p.y, p.z;
      if (mesh->HasVertexColors(0)) {
        const aiColor4D& c = mesh->mColors[0][v];
        out.colors.row(vbase + v) << c.r, c.g, c.b;
      }
    }
    for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
      const aiFace& face = mesh->mFaces[f];
      if (triangles_of(face) == 0) continue;
      for (unsigned k = 0; k < face.mNumIndices; ++k)
        require(face.mIndices[k] < mesh->mNumVertices, path, ": a face refers to vertex ", face.mIndices[k],
                " of a mesh with ", mesh->mNumVertices, " vertices");
      for (unsigned t = 0; t < triangles_of(face); ++t)
        out.faces.row(fi++) << int(vbase + face.mIndices[0]), int(vbase + face.mIndices[t + 1]),
            int(vbase + face.mIndices[t + 2]);
    }
    vbase += mesh->mNumVertices;
  }
  require(out.vertices.allFinite(), path, ": vertex positions contain NaN or Inf");
  return out;
}

}  // namespace

ImportedMesh read_mesh(const std::string& path) {
  require(fs::exists(path), path, ": no such file");
  {
    std::ifstream in(path, std::ios::binary);
    char magic[3] = {};
    in.read(magic, 3);
    if (in.gcount() == 3 && std::string_view(magic, 3) == "ply") {  // assimp trusts PLY headers: check first
      in.seekg(0);
      const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
      check_ply_structure(bytes, path);
    }
  }
  auto read = [&] {
    Assimp::Importer importer;
    const aiScene* scene = importer.ReadFile(path, kImportSteps);
    if (!scene) fail(path, ": cannot read mesh: ", importer.GetErrorString());
    return imported_triangles(scene, path);
  };
  return read_in_child_first(path, read);
}

ImportedMesh read_mesh_from_memory(const void* data, std::size_t size, const std::string& format,
                                   const std::string& name) {
  require(size > 0, name, ": empty mesh file");
  check_ply_structure(std::string_view(static_cast<const char*>(data), size), name);
  auto read = [&] {
    Assimp::Importer importer;
    const aiScene* scene = importer.ReadFileFromMemory(data, size, kImportSteps, format.c_str());
    if (!scene) fail(name, ": cannot read mesh: ", importer.GetErrorString());
    return imported_triangles(scene, name);
  };
  return read_in_child_first(name, read);
}

}  // namespace sflsh::io
