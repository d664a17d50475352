#include "sflsh/io/ply_structure.hpp"

#include <cstdint>
#include <cstring>
#include <sstream>
#include <vector>

#include "sflsh/core/error.hpp"

namespace sflsh::io {
namespace {

// Bytes of a PLY scalar type (both the PLY 1.0 names and the sized ones); 0 if unknown.
int scalar_bytes(const std::string& type) {
  if (type == "char" || type == "uchar" || type == "int8" || type == "uint8") return 1;
  if (type == "short" || type == "ushort" || type == "int16" || type == "uint16") return 2;
  if (type == "int" || type == "uint" || type == "float" || type == "int32" || type == "uint32" || type == "float32")
    return 4;
  if (type == "double" || type == "float64") return 8;
  return 0;
}

struct Property {
  int bytes = 0;        // scalar, or a list's item
  int count_bytes = 0;  // > 0 for a list: bytes of its count
  bool count_signed = false;
  bool item_signed = false;
  bool vertex_indices = false;  // a face's vertex_indices / vertex_index list
};

struct Element {
  std::string name;
  std::uint64_t count = 0;
  std::vector<Property> properties;
};

// An integer of `bytes` bytes at `p` (unsigned or two's complement), in the file's byte order.
std::int64_t read_integer(const unsigned char* p, int bytes, bool is_signed, bool big_endian) {
  std::uint64_t v = 0;
  for (int i = 0; i < bytes; ++i) v |= std::uint64_t(p[big_endian ? i : bytes - 1 - i]) << (8 * (bytes - 1 - i));
  if (is_signed && bytes < 8 && (v >> (8 * bytes - 1)) != 0) return std::int64_t(v) - (std::int64_t(1) << (8 * bytes));
  return std::int64_t(v);
}

/// A PLY header: its format, elements and where the body starts.
struct PlyHeader {
  std::string format;
  std::vector<Element> elements;
  std::size_t body = std::string_view::npos;
};

/// Reads the header: lines, each starting with one of PLY's keywords, up to a line that is
/// exactly "end_header". A damaged keyword, or "end_header" inside another line, made this
/// walk and assimp's disagree on where the body starts: assimp then ran out of bounds or
/// looped for minutes (scripts/fuzz.sh, mesh). So every line is checked, not searched.
PlyHeader read_ply_header(std::string_view bytes, const std::string& path) {
  PlyHeader h;
  std::string& format = h.format;
  std::vector<Element>& elements = h.elements;
  std::size_t& body = h.body;
  int line_no = 0;
  std::size_t at_line = 0;
  while (at_line < bytes.size()) {
    const std::size_t nl = bytes.find('\n', at_line);
    require(nl != std::string_view::npos, path, ": PLY header without an end_header line (truncated file?)");
    std::string line(bytes.substr(at_line, nl - at_line));
    at_line = nl + 1;
    ++line_no;
    while (!line.empty() && (line.back() == '\r' || line.back() == ' ' || line.back() == '\t')) line.pop_back();
    if (line == "end_header") {
      body = at_line;
      break;
    }
    std::istringstream words(line);
    std::string keyword;
    words >> keyword;
    if (line_no == 1) {
      require(line == "ply", path, ": PLY file's first line is '", line.substr(0, 40), "', expected 'ply'");
    } else if (keyword == "comment" || keyword == "obj_info") {
    } else if (keyword == "format") {
      words >> format;
    } else if (keyword == "element") {
      Element e;
      long long count = -1;
      words >> e.name >> count;
      require(!words.fail() && count >= 0, path, ": PLY header line ", line_no, " '", line,
              "': expected 'element NAME COUNT' with COUNT >= 0");
      e.count = std::uint64_t(count);
      elements.push_back(e);
    } else if (keyword == "property") {
      require(!elements.empty(), path, ": PLY header line ", line_no, ": a property before any element");
      std::string type;
      words >> type;
      Property p;
      if (type == "list") {
        std::string count_type, item_type;
        words >> count_type >> item_type;
        p.count_bytes = scalar_bytes(count_type);
        p.count_signed = count_type[0] != 'u';
        p.bytes = scalar_bytes(item_type);
        p.item_signed = item_type[0] != 'u';
        std::string name;
        words >> name;
        p.vertex_indices = elements.back().name == "face" && (name == "vertex_indices" || name == "vertex_index");
        require(p.count_bytes > 0 && p.count_bytes <= 4 && p.bytes > 0 && count_type.find("float") == std::string::npos &&
                    count_type != "double",
                path, ": PLY header line ", line_no, " '", line, "': unsupported list types");
      } else {
        p.bytes = scalar_bytes(type);
        require(p.bytes > 0, path, ": PLY header line ", line_no, " '", line, "': unknown property type '", type, "'");
      }
      elements.back().properties.push_back(p);
    } else if (keyword.rfind("end_header", 0) == 0) {
      fail(path, ": PLY header's end_header is not followed by a line end (truncated or damaged file?)");
    } else {
      require(keyword.empty(), path, ": PLY header line ", line_no, " starts with '", keyword.substr(0, 40),
              "', not a PLY keyword (ply, format, comment, obj_info, element, property, end_header): a damaged file?");
    }
  }
  return h;
}

/// Walks a binary PLY body: every element's rows fit in the bytes left, list
/// counts are non-negative and faces refer to existing vertices.
void check_ply_body(std::string_view bytes, const std::string& path, const PlyHeader& h) {
  const std::vector<Element>& elements = h.elements;
  const bool big_endian = h.format == "binary_big_endian";
  std::uint64_t num_vertices = 0;
  for (const Element& e : elements)
    if (e.name == "vertex") num_vertices = e.count;
  const auto* data = reinterpret_cast<const unsigned char*>(bytes.data());
  const std::size_t size = bytes.size();
  std::size_t at = h.body;
  for (const Element& e : elements) {
    bool has_list = false;
    std::size_t fixed = 0;
    for (const Property& p : e.properties) {
      has_list |= p.count_bytes > 0;
      fixed += std::size_t(p.bytes);
    }
    if (!has_list) {  // fixed-size rows: one bound, no walk
      const std::uint64_t need = fixed * e.count;
      require(fixed == 0 || (e.count <= (size - at) / fixed && need <= size - at), path, ": PLY body is truncated: element '",
              e.name, "' declares ", e.count, " rows of ", fixed, " bytes, but ", size - at, " bytes are left");
      at += std::size_t(need);
      continue;
    }
    for (std::uint64_t i = 0; i < e.count; ++i) {
      for (const Property& p : e.properties) {
        if (p.count_bytes == 0) {
          require(size - at >= std::size_t(p.bytes), path, ": PLY body is truncated in element '", e.name, "' row ", i,
                  " of ", e.count);
          at += std::size_t(p.bytes);
          continue;
        }
        require(size - at >= std::size_t(p.count_bytes), path, ": PLY body is truncated in element '", e.name, "' row ",
                i, " of ", e.count);
        const std::int64_t n = read_integer(data + at, p.count_bytes, p.count_signed, big_endian);
        at += std::size_t(p.count_bytes);
        require(n >= 0, path, ": PLY element '", e.name, "' row ", i, " has a list of ", n, " items");
        require(std::uint64_t(n) <= (size - at) / std::size_t(p.bytes), path, ": PLY body is truncated in element '",
                e.name, "' row ", i, " of ", e.count, " (a list of ", n, " items, ", size - at, " bytes left)");
        if (p.vertex_indices && p.bytes <= 4) {  // the loader indexes the vertices with these
          for (std::int64_t k = 0; k < n; ++k) {
            const std::int64_t v = read_integer(data + at + std::size_t(k) * std::size_t(p.bytes), p.bytes, p.item_signed,
                                              big_endian);
            require(v >= 0 && std::uint64_t(v) < num_vertices, path, ": PLY face ", i, " refers to vertex ", v, " of ",
                    num_vertices);
          }
        }
        at += std::size_t(n) * std::size_t(p.bytes);
      }
    }
  }
}

}  // namespace

void check_ply_structure(std::string_view bytes, const std::string& path) {
  if (bytes.substr(0, 3) != "ply") return;
  const PlyHeader h = read_ply_header(bytes, path);
  const std::size_t body = h.body;
  const std::string& format = h.format;
  require(body != std::string_view::npos, path, ": PLY header without an end_header line (truncated file?)");
  require(format == "ascii" || format == "binary_little_endian" || format == "binary_big_endian", path,
          ": PLY header has no known format line (got '", format, "')");
  if (format == "ascii") return;  // assimp's text parser stops at the end of the text

  check_ply_body(bytes, path, h);
}

}  // namespace sflsh::io
