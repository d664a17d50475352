// check_ply_structure against PLY files built byte by byte here: one valid tetrahedron in each
// byte order and in text, then one damage at a time. Each damaged file once crashed or hung
// assimp's PLY reader (scripts/fuzz.sh), so the check must refuse it with the file's name.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <string>

#include "sflsh/core/error.hpp"
#include "sflsh/io/mesh_export.hpp"
#include "sflsh/io/ply_structure.hpp"

using namespace sflsh;

namespace {

template <class T>
void put(std::string& out, T value, bool big_endian) {
  char b[sizeof(T)];
  std::memcpy(b, &value, sizeof(T));
  if (big_endian)
    for (size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
  out.append(b, sizeof(T));
}

// A closed tetrahedron: 4 vertices (float x y z), 4 faces (uchar count, int indices).
std::string binary_tetrahedron(bool big_endian, int bad_index = -1, const std::string& after_end_header = "\n") {
  std::string s = std::string("ply\nformat ") + (big_endian ? "binary_big_endian" : "binary_little_endian") +
                  " 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
                  "element face 4\nproperty list uchar int vertex_indices\nend_header" +
                  after_end_header;
  const float v[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  for (const auto& p : v)
    for (float c : p) put(s, c, big_endian);
  const int f[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  for (int i = 0; i < 4; ++i) {
    put(s, std::uint8_t(3), big_endian);
    for (int k = 0; k < 3; ++k) put(s, std::int32_t(i == 3 && k == 2 && bad_index != -1 ? bad_index : f[i][k]), big_endian);
  }
  return s;
}

std::string replace_first(std::string s, const std::string& what, const std::string& with) {
  const size_t at = s.find(what);
  EXPECT_NE(at, std::string::npos) << what;
  return at == std::string::npos ? s : s.replace(at, what.size(), with);
}

std::string error_of(const std::string& bytes) {
  try {
    io::check_ply_structure(bytes, "probe.ply");
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(PlyStructure, ValidFilesPassAndAssimpReadsThem) {
  for (bool be : {false, true}) {
    const std::string bytes = binary_tetrahedron(be);
    EXPECT_EQ(error_of(bytes), "") << (be ? "big" : "little");
    const io::ImportedMesh m = io::read_mesh_from_memory(bytes.data(), bytes.size(), "ply", "probe.ply");
    EXPECT_EQ(m.faces.rows(), 4);
    EXPECT_EQ(m.vertices.rows(), 4);
  }
  EXPECT_EQ(error_of(binary_tetrahedron(false, -1, "\r\n")), "");
  const std::string text =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  EXPECT_EQ(error_of(text), "");
  EXPECT_EQ(error_of("solid x\nendsolid x\n"), "");  // not a PLY file: not this check's business
}

TEST(PlyStructure, DamagedFilesAreOneErrorNamingTheFile) {
  const std::string good = binary_tetrahedron(false);
  struct Case {
    std::string bytes, expected;
  };
  const Case cases[] = {
      {good.substr(0, good.size() - 1), "PLY body is truncated in element 'face' row 3 of 4"},
      {good.substr(0, good.find("end_header") + 11 + 20), "element 'vertex' declares 4 rows of 12 bytes, but 20"},
      {good.substr(0, good.find("end_header")), "without an end_header line"},
      {binary_tetrahedron(false, 4), "PLY face 3 refers to vertex 4 of 4"},
      {binary_tetrahedron(false, -7), "PLY face 3 refers to vertex -7 of 4"},
      {binary_tetrahedron(true, 1000), "PLY face 3 refers to vertex 1000 of 4"},
      {binary_tetrahedron(false, -1, "\xcc\xbd\n"), "end_header is not followed by a line end"},
      {"ply\nformat binary_little_endian 1.0\nelement vertex -3\nend_header\n", "COUNT >= 0"},
      {"ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty quad x\nend_header\n", "unknown property type 'quad'"},
      {"ply\nformat binary_little_endian 1.0\nelement face 1\nproperty list float int vertex_indices\nend_header\n",
       "unsupported list types"},
      {"ply\nformat binary_middle_endian 1.0\nend_header\n", "no known format line"},
      // Header lines must start with a keyword, and end_header must be a line of its own:
      // where this walk and assimp's disagreed on the body's start, assimp crashed or hung.
      {"ply\nformat binary_little_endian 1.0\nelem\xae" "ent face 48\nend_header\n", "line 3 starts with 'elem"},
      {replace_first(good, "end_header", "Aend_header\nend_header"), "line 9 starts with 'Aend_header'"},
      {replace_first(good, "ply\n", "ply junk\n"), "first line is 'ply junk', expected 'ply'"},
      {"ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\nend_header\n\x01\x02",
       "declares 4000000000 rows of 4 bytes, but 2 bytes are left"},
  };
  for (const Case& c : cases) {
    const std::string what = error_of(c.bytes);
    EXPECT_NE(what.find("probe.ply: "), std::string::npos) << what;
    EXPECT_NE(what.find(c.expected), std::string::npos) << "expected '" << c.expected << "', got '" << what << "'";
  }
}

}  // namespace
