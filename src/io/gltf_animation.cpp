#include "sflsh/io/gltf_animation.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>

#include "sflsh/core/error.hpp"
#include "sflsh/io/atomic_output.hpp"
#include "sflsh/io/surface_normals.hpp"

namespace sflsh::io {

namespace {

// glTF 2.0 enumerations (spec §3.6.2.2 and §3.6.1).
constexpr int kFloat = 5126, kUnsignedInt = 5125;
constexpr int kArrayBuffer = 34962, kElementArrayBuffer = 34963;

/// Binary buffer plus the JSON of its bufferViews and accessors, built together
/// so that offsets and indices can not disagree.
class GltfBuffers {
 public:
  /// Appends float32 data as a new bufferView + accessor; returns the accessor index.
  /// `type` is "SCALAR", "VEC3" or "VEC4"; `with_bounds` adds min/max (required for POSITION).
  int add_floats(const std::vector<float>& values, const char* type, int target, bool with_bounds) {
    const int comps = std::strcmp(type, "VEC3") == 0 ? 3 : std::strcmp(type, "VEC4") == 0 ? 4 : 1;
    std::string bounds;
    if (with_bounds) {
      float lo[4] = {INFINITY, INFINITY, INFINITY, INFINITY}, hi[4] = {-INFINITY, -INFINITY, -INFINITY, -INFINITY};
      for (size_t i = 0; i < values.size(); ++i) {
        lo[i % size_t(comps)] = std::min(lo[i % size_t(comps)], values[i]);
        hi[i % size_t(comps)] = std::max(hi[i % size_t(comps)], values[i]);
      }
      bounds = ",\"min\":[" + list(lo, comps) + "],\"max\":[" + list(hi, comps) + "]";
    }
    return add(values.data(), values.size() * 4, kFloat, values.size() / size_t(comps), type, target, bounds);
  }
  int add_indices(const std::vector<std::uint32_t>& values) {
    return add(values.data(), values.size() * 4, kUnsignedInt, values.size(), "SCALAR", kElementArrayBuffer, "");
  }
  const std::string& bin() const { return bin_; }
  std::string views_json() const { return "[" + views_ + "]"; }
  std::string accessors_json() const { return "[" + accessors_ + "]"; }

 private:
  static std::string list(const float* v, int n) {
    std::string s;
    for (int i = 0; i < n; ++i) {
      char buf[32];
      std::snprintf(buf, sizeof buf, "%s%.9g", i ? "," : "", double(v[i]));
      s += buf;
    }
    return s;
  }
  int add(const void* data, size_t bytes, int component, size_t count, const char* type, int target,
          const std::string& bounds) {
    // Every element here is 4 bytes, so 4-byte alignment of each view suffices.
    const size_t offset = bin_.size();
    // Little-endian host assumed for the raw copy (x86-64 / arm64 Linux).
    bin_.append(static_cast<const char*>(data), bytes);
    std::ostringstream v, a;
    v << (views_.empty() ? "" : ",") << "{\"buffer\":0,\"byteOffset\":" << offset << ",\"byteLength\":" << bytes;
    if (target) v << ",\"target\":" << target;
    v << "}";
    a << (accessors_.empty() ? "" : ",") << "{\"bufferView\":" << num_ << ",\"componentType\":" << component
      << ",\"count\":" << count << ",\"type\":\"" << type << "\"" << bounds << "}";
    views_ += v.str();
    accessors_ += a.str();
    return num_++;
  }
  std::string bin_, views_, accessors_;
  int num_ = 0;
};

std::vector<float> to_floats(const Points& P) {
  std::vector<float> out(size_t(P.size()));
  for (Eigen::Index i = 0; i < P.rows(); ++i)
    for (int c = 0; c < 3; ++c) out[size_t(i) * 3 + size_t(c)] = float(P(i, c));
  return out;
}

void put_u32(std::string& s, std::uint32_t x) {
  for (int i = 0; i < 4; ++i) s.push_back(char((x >> (8 * i)) & 0xff));
}

/// `s` as a JSON string literal (quotes, backslashes and control characters escaped).
std::string json_string(const std::string& s) {
  std::string out = "\"";
  for (unsigned char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += char(c);
    } else if (c < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", c);
      out += buf;
    } else {
      out += char(c);
    }
  }
  return out + "\"";
}

std::string json_numbers(std::initializer_list<double> values) {
  std::ostringstream o;
  o.precision(9);
  o << "[";
  for (auto it = values.begin(); it != values.end(); ++it) o << (it == values.begin() ? "" : ",") << *it;
  return o.str() + "]";
}

/// Indices, positions and normals of one triangle mesh; returns the primitive's
/// JSON without the closing brace (targets or material may follow).
std::string add_mesh_primitive(GltfBuffers& buf, const Points& V, const Triangles& F, const Points& colors) {
  std::vector<std::uint32_t> idx(size_t(F.size()));
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int c = 0; c < 3; ++c) idx[size_t(f) * 3 + size_t(c)] = std::uint32_t(F(f, c));
  const int indices = buf.add_indices(idx);
  const int position = buf.add_floats(to_floats(V), "VEC3", kArrayBuffer, true);
  const int normal = buf.add_floats(to_floats(vertex_normals(V, F)), "VEC3", kArrayBuffer, false);
  std::ostringstream js;
  js << "{\"attributes\":{\"POSITION\":" << position << ",\"NORMAL\":" << normal;
  if (colors.rows())
    js << ",\"COLOR_0\":" << buf.add_floats(to_floats(colors.cwiseMax(0.0).cwiseMin(1.0)), "VEC3", kArrayBuffer, false);
  js << "},\"indices\":" << indices << ",\"mode\":4";
  return js.str();
}

/// A rigid node's rotations as glTF keys (x y z w), each on the hemisphere of
/// the previous one.
std::vector<float> rotation_keys(const std::vector<Eigen::Quaterniond>& q) {
  std::vector<float> out;
  Eigen::Quaterniond prev = q.front();
  for (Eigen::Quaterniond r : q) {
    if (r.coeffs().dot(prev.coeffs()) < 0) r.coeffs() *= -1.0;
    for (int c = 0; c < 4; ++c) out.push_back(float(r.coeffs()[c]));  // Eigen stores x y z w
    prev = r;
  }
  return out;
}

void check_rigid_node(const std::string& path, const GltfRigidNode& n, size_t num_frames) {
  const std::string at = path + ": rigid node '" + n.name + "'";
  require(n.vertices.rows() > 0 && n.faces.rows() > 0, at, " has no surface");
  require(n.vertices.allFinite(), at, ": vertices contain NaN or Inf");
  require(n.faces.minCoeff() >= 0 && n.faces.maxCoeff() < n.vertices.rows(), at, ": face indices must lie in [0, ",
          n.vertices.rows(), ")");
  require(n.translations.size() == num_frames && n.rotations.size() == num_frames, at, " has ", n.translations.size(),
          " translations and ", n.rotations.size(), " rotations for ", num_frames, " frames");
  for (size_t k = 0; k < num_frames; ++k) {
    require(n.translations[k].allFinite() && n.rotations[k].coeffs().allFinite(), at, ": pose ", k, " is not finite");
    require(std::abs(n.rotations[k].norm() - 1.0) < 1e-6, at, ": rotation ", k, " is not a unit quaternion (norm ",
            n.rotations[k].norm(), ")");
  }
  require(n.color.allFinite(), at, ": colour must be finite");
}

/// Writes a GLB container (spec §4.4): 12-byte header, JSON chunk padded with
/// spaces, BIN chunk padded with zeros, both to 4 bytes.
void write_glb(const std::string& path, std::string json, std::string bin) {
  json.append((4 - json.size() % 4) % 4, ' ');
  bin.append((4 - bin.size() % 4) % 4, '\0');
  std::string glb;
  put_u32(glb, 0x46546C67u);  // "glTF"
  put_u32(glb, 2);
  put_u32(glb, std::uint32_t(12 + 8 + json.size() + 8 + bin.size()));
  put_u32(glb, std::uint32_t(json.size()));
  put_u32(glb, 0x4E4F534Au);  // "JSON"
  AtomicOutput out(path);
  std::ofstream os(out.temp_path(), std::ios::binary);
  require(bool(os), path, ": cannot open ", out.temp_path(), " for writing");
  os.write(glb.data(), std::streamsize(glb.size()));
  os.write(json.data(), std::streamsize(json.size()));
  std::string bin_header;
  put_u32(bin_header, std::uint32_t(bin.size()));
  put_u32(bin_header, 0x004E4942u);  // "BIN\0"
  os.write(bin_header.data(), 8);
  os.write(bin.data(), std::streamsize(bin.size()));
  os.close();
  require(bool(os), path, ": write failed (disk full?)");
  out.commit();
}

}  // namespace

void write_animated_glb(const std::string& path, const std::vector<Points>& frames, const Triangles& F, double fps,
                        const Points& colors, const std::vector<GltfRigidNode>& rigid) {
  require(lower_extension(path) == ".glb", path, ": an animated glTF is written as .glb");
  require(!frames.empty(), path, ": no frames to write");
  require(std::isfinite(fps) && fps > 0, path, ": fps must be positive, got ", fps);
  const Eigen::Index nv = frames.front().rows();
  for (size_t k = 0; k < frames.size(); ++k) {
    require(frames[k].rows() == nv, path, ": frame ", k, " has ", frames[k].rows(), " vertices, expected ", nv);
    require(frames[k].allFinite(), path, ": frame ", k, " contains NaN or Inf");
  }
  require(F.rows() > 0 && F.minCoeff() >= 0 && F.maxCoeff() < nv, path, ": face indices must lie in [0, ", nv, ")");
  require(colors.rows() == 0 || colors.rows() == nv, path, ": colors has ", colors.rows(), " rows, expected ", nv);
  for (const GltfRigidNode& n : rigid) check_rigid_node(path, n, frames.size());

  GltfBuffers buf;
  const std::string skin = add_mesh_primitive(buf, frames.front(), F, colors);
  const Points n0 = vertex_normals(frames.front(), F);
  const size_t num_targets = frames.size() - 1;
  std::ostringstream targets;
  for (size_t k = 1; k < frames.size(); ++k) {
    const int dp = buf.add_floats(to_floats(frames[k] - frames.front()), "VEC3", kArrayBuffer, true);
    const int dn = buf.add_floats(to_floats(vertex_normals(frames[k], F) - n0), "VEC3", kArrayBuffer, false);
    targets << (k > 1 ? "," : "") << "{\"POSITION\":" << dp << ",\"NORMAL\":" << dn << "}";
  }
  std::vector<std::string> rigid_meshes;
  for (const GltfRigidNode& n : rigid) rigid_meshes.push_back(add_mesh_primitive(buf, n.vertices, n.faces, Points()));

  // Animation: keyframe k at time k/fps. The skin's weights are one-hot on
  // target k-1 (all zero at k = 0); rigid nodes whose pose changes get
  // translation and rotation channels.
  std::ostringstream samplers, channels;
  int num_samplers = 0, times = -1;
  auto add_channel = [&](int node, const char* target_path, int output) {
    if (times < 0) {
      std::vector<float> t(frames.size());
      for (size_t k = 0; k < frames.size(); ++k) t[k] = float(double(k) / fps);
      times = buf.add_floats(t, "SCALAR", 0, true);  // sampler input needs min/max
    }
    samplers << (num_samplers ? "," : "") << "{\"input\":" << times << ",\"output\":" << output
             << ",\"interpolation\":\"LINEAR\"}";
    channels << (num_samplers ? "," : "") << "{\"sampler\":" << num_samplers << ",\"target\":{\"node\":" << node
             << ",\"path\":\"" << target_path << "\"}}";
    ++num_samplers;
  };
  if (num_targets) {
    std::vector<float> weights(frames.size() * num_targets, 0.f);
    for (size_t k = 1; k < frames.size(); ++k) weights[k * num_targets + (k - 1)] = 1.f;
    add_channel(0, "weights", buf.add_floats(weights, "SCALAR", 0, false));
  }
  for (size_t i = 0; i < rigid.size(); ++i) {
    const GltfRigidNode& n = rigid[i];
    bool moves = false;
    for (size_t k = 1; k < frames.size(); ++k)
      moves = moves || n.translations[k] != n.translations[0] || n.rotations[k].coeffs() != n.rotations[0].coeffs();
    if (!moves) continue;
    Points t(Eigen::Index(frames.size()), 3);
    for (size_t k = 0; k < frames.size(); ++k) t.row(Eigen::Index(k)) = n.translations[k].transpose();
    add_channel(int(i) + 1, "translation", buf.add_floats(to_floats(t), "VEC3", 0, false));
    add_channel(int(i) + 1, "rotation", buf.add_floats(rotation_keys(n.rotations), "VEC4", 0, false));
  }

  std::ostringstream js;
  js << "{\"asset\":{\"version\":\"2.0\",\"generator\":\"sflsh\",\"extras\":{\"units\":\"metres\",\"fps\":" << fps
     << "}},\"scene\":0,\"scenes\":[{\"nodes\":[0";
  for (size_t i = 0; i < rigid.size(); ++i) js << "," << i + 1;
  js << "]}],\"nodes\":[{\"mesh\":0,\"name\":\"body\"}";
  for (size_t i = 0; i < rigid.size(); ++i) {
    const Eigen::Quaterniond& q = rigid[i].rotations.front();
    const Vec3& t = rigid[i].translations.front();
    js << ",{\"mesh\":" << i + 1 << ",\"name\":" << json_string(rigid[i].name)
       << ",\"translation\":" << json_numbers({t.x(), t.y(), t.z()})
       << ",\"rotation\":" << json_numbers({q.x(), q.y(), q.z(), q.w()}) << "}";
  }
  js << "],\"materials\":[{\"name\":\"skin\",\"pbrMetallicRoughness\":{\"baseColorFactor\":"
     << (colors.rows() ? "[1,1,1,1]" : "[0.87,0.7,0.6,1]") << ",\"metallicFactor\":0,\"roughnessFactor\":0.7}}";
  for (const GltfRigidNode& n : rigid)
    js << ",{\"name\":" << json_string(n.name) << ",\"pbrMetallicRoughness\":{\"baseColorFactor\":"
       << json_numbers({n.color.x(), n.color.y(), n.color.z(), 1.0}) << ",\"metallicFactor\":0,\"roughnessFactor\":0.8}"
       << (n.double_sided ? ",\"doubleSided\":true" : "") << "}";
  js << "],\"meshes\":[{\"name\":\"body\",\"primitives\":[" << skin << ",\"material\":0";
  if (num_targets) {
    js << ",\"targets\":[" << targets.str() << "]}],\"weights\":[";
    for (size_t t = 0; t < num_targets; ++t) js << (t ? ",0" : "0");
    js << "]}";
  } else {
    js << "}]}";
  }
  for (size_t i = 0; i < rigid.size(); ++i)
    js << ",{\"name\":" << json_string(rigid[i].name) << ",\"primitives\":[" << rigid_meshes[i] << ",\"material\":" << i + 1
       << "}]}";
  js << "]";
  if (num_samplers)
    js << ",\"animations\":[{\"name\":\"simulation\",\"samplers\":[" << samplers.str() << "],\"channels\":["
       << channels.str() << "]}]";
  js << ",\"buffers\":[{\"byteLength\":" << buf.bin().size() << "}],\"bufferViews\":" << buf.views_json()
     << ",\"accessors\":" << buf.accessors_json() << "}";

  write_glb(path, js.str(), buf.bin());
}

}  // namespace sflsh::io
