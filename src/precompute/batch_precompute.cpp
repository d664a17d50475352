#include "sflsh/precompute/batch_precompute.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <map>
#include <sstream>

#include "sflsh/asset/avatar_file.hpp"
#include "sflsh/body/body_model_io.hpp"
#include "sflsh/core/child_processes.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/core/fnv_hash.hpp"
#include "sflsh/core/memory.hpp"
#include "sflsh/core/timer.hpp"
#include "sflsh/io/atomic_output.hpp"
#include "sflsh/io/crash_isolation.hpp"
#include "sflsh/io/hdf5_file.hpp"
#include "sflsh/mesh/tet_topology_hash.hpp"

namespace sflsh {
namespace fs = std::filesystem;
namespace {

const char* kManifestHeader = "row,line,name,key,file,status,topology,seconds,peak_rss_mib,error";
// Manifests written before the topology column; still read (topology "").
const char* kManifestHeaderWithoutTopology = "row,line,name,key,file,status,seconds,peak_rss_mib,error";

std::string trim(const std::string& s) {
  const size_t a = s.find_first_not_of(" \t"), b = s.find_last_not_of(" \t");
  return a == std::string::npos ? std::string() : s.substr(a, b - a + 1);
}

/// Splits one CSV line; fields may be double-quoted ("" is a quote inside).
/// Unquoted fields are trimmed.
std::vector<std::string> split_csv(const std::string& line) {
  std::vector<std::string> out;
  std::string field;
  bool quoted = false, was_quoted = false;
  for (size_t i = 0; i <= line.size(); ++i) {
    const char c = i < line.size() ? line[i] : ',';
    if (quoted) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
        field += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        field += c;
      }
    } else if (c == '"' && trim(field).empty()) {
      quoted = was_quoted = true;
      field.clear();
    } else if (c == ',') {
      out.push_back(was_quoted ? field : trim(field));
      field.clear();
      was_quoted = false;
    } else if (!was_quoted) {
      field += c;
    }
  }
  return out;
}

std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) {
    if (c == '\n' || c == '\r') c = ' ';
    q += c;
    if (c == '"') q += '"';
  }
  return q + "\"";
}

/// A number as strtod reads it, the whole field (NaN and inf included).
bool parse_number(const std::string& field, double* v) {
  if (field.empty()) return false;
  char* end = nullptr;
  errno = 0;
  *v = std::strtod(field.c_str(), &end);
  return *end == '\0' && errno != ERANGE;
}

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return s;
}

/// The error of a data row, "" when it is usable; fills *betas and *name.
std::string parse_row(const std::vector<std::string>& fields, const std::vector<std::string>& header, int name_col,
                      int model_betas, VecX* betas, std::string* name) {
  if (!header.empty() && fields.size() != header.size())
    return "has " + std::to_string(fields.size()) + " fields but the header has " + std::to_string(header.size());
  if (name_col >= 0) *name = fields[name_col];
  std::vector<double> b;
  for (size_t j = 0; j < fields.size(); ++j) {
    if (int(j) == name_col) continue;
    const std::string col = header.empty() ? "β " + std::to_string(b.size()) : "column '" + header[j] + "'";
    double v = 0;
    if (fields[j].empty()) return col + " is empty (expected a number)";
    if (!parse_number(fields[j], &v)) return col + " '" + fields[j] + "' is not a number";
    if (!std::isfinite(v)) return col + " is " + fields[j] + " (β must be finite)";
    b.push_back(v);
  }
  if (int(b.size()) > model_betas)
    return "has " + std::to_string(b.size()) + " β values but the model has " + std::to_string(model_betas) +
           " shape directions";
  *betas = VecX::Zero(model_betas);
  for (size_t j = 0; j < b.size(); ++j) (*betas)[Eigen::Index(j)] = b[j];
  return "";
}

std::string fixed(double v, int digits) {
  std::ostringstream o;
  o << std::fixed << std::setprecision(digits) << v;
  return o.str();
}

std::string duration(double s) {
  if (s < 90) return fixed(s, 0) + " s";
  if (s < 5400) return fixed(s / 60, 1) + " min";
  return fixed(s / 3600, 1) + " h";
}

}  // namespace

std::vector<BatchShape> read_batch_shapes(const std::string& path, int model_betas) {
  std::ifstream in(path);
  if (!in) fail(path, ": cannot open the shapes file");
  std::vector<BatchShape> rows;
  std::vector<std::string> header;
  int name_col = -1;
  bool first = true;
  std::string line;
  int lineno = 0;
  while (std::getline(in, line)) {
    ++lineno;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (trim(line).empty() || trim(line)[0] == '#') continue;
    const std::vector<std::string> fields = split_csv(line);
    if (first) {
      first = false;
      double v;
      const bool numeric = std::all_of(fields.begin(), fields.end(), [&](const std::string& f) {
        return parse_number(f, &v);
      });
      if (!numeric) {
        header = fields;
        for (size_t j = 0; j < header.size(); ++j) {
          if (lower(header[j]) != "name") continue;
          if (name_col >= 0) fail(path, ":", lineno, ": the header has two 'name' columns");
          name_col = int(j);
        }
        continue;
      }
    }
    BatchShape s;
    s.row = int(rows.size());
    s.line = lineno;
    s.error = parse_row(fields, header, name_col, model_betas, &s.betas, &s.name);
    if (!s.error.empty()) s.betas.resize(0);
    rows.push_back(std::move(s));
  }
  if (rows.empty()) fail(path, ": no data rows (expected one β vector per line, e.g. 0.5,-1,2)");
  return rows;
}

namespace {

/// Everything in the content key except β (hashing the model costs ~tens of
/// ms: plan_batch computes this once for all rows).
std::string key_prefix(const BodyModel& model, const PrecomputeOptions& o) {
  std::ostringstream s;
  s << std::setprecision(17) << "avatar|" << kAvatarFormatVersion << '|' << body_model_hash(model) << '|'
    << template_cache_key(model, o.template_stage);
  const ShapeOptions& so = o.shape_stage;
  s << "|shape," << so.min_depth << ',' << so.scale_smoothing_iterations << ',' << so.capsule_percentile << ','
    << so.max_relax_rounds << ',' << so.min_dihedral_deg << ',' << so.quality_floor_deg << ',' << so.smoothing.target_deg
    << ',' << so.smoothing.passes << ',' << so.smoothing.max_displacement_fraction << ',' << so.skin_slide_fraction
    << "|thickness";
  for (const auto& [region, scale] : o.thickness.scale) s << ',' << region << '=' << scale;
  s << "|handles," << o.handles << ',' << o.handle_positions.rows();
  for (Eigen::Index i = 0; i < o.handle_positions.size(); ++i) s << ',' << o.handle_positions.data()[i];
  s << "|placement," << o.placement.thickness_exponent << ',' << o.placement.seed;
  // 2: the earlier minimum, which the keys of files built with it did not spell out.
  if (o.placement.min_per_region != 2) s << ",min_per_region," << o.placement.min_per_region;
  s << "|bbw," << o.bbw.max_iterations << ',' << o.bbw.pdas_iterations << ',' << o.bbw.multiplier_tolerance << ','
    << o.bbw.drop_tolerance << ',' << o.bbw.initial_radius_factor << ',' << o.bbw.max_border_columns << ','
    << int(o.bbw.bone_condition) << ',' << o.bbw.normalization_floor << ',' << o.bbw.kkt_tolerance << ',' << o.bbw.max_releases;
  s << "|cubature," << o.elastic_samples_per_cell << ',' << o.fit_elastic_cubature;
  if (o.inertia_samples_per_cell > 0) s << ",inertia," << o.inertia_samples_per_cell;  // keys of older files unchanged
  s << "|betas";
  return s.str();
}

std::string key_of(const std::string& prefix, const VecX& betas) {
  std::ostringstream s;
  s << std::setprecision(17) << prefix;
  for (Eigen::Index i = 0; i < betas.size(); ++i) s << ',' << betas[i];
  Fnv1a64 h;
  h.add(s.str());
  return h.hex();
}

}  // namespace

std::string avatar_content_key(const BodyModel& model, const VecX& betas, const PrecomputeOptions& o) {
  return key_of(key_prefix(model, o), betas);
}

std::string batch_avatar_file_name(const std::string& key) { return "avatar-" + key + ".h5"; }

bool batch_output_done(const std::string& path, const std::string& model_hash, const VecX& betas) {
  std::error_code ec;
  if (!fs::exists(path, ec)) return false;
  auto check = [&] {
    const io::Hdf5File f(path, io::Hdf5File::Mode::Read);
    if (!f.has("/meta/betas") || !f.has("/meta/model_hash")) return false;
    if (f.read_string("/meta/model_hash") != model_hash) return false;
    const MatXr b = f.read_matrix("/meta/betas");
    if (b.size() != betas.size()) return false;
    return std::equal(b.data(), b.data() + b.size(), betas.data());
  };
  try {
    return io::read_in_child_first(path, check);  // a file that crashes libhdf5 is refused (io/crash_isolation.hpp)
  } catch (const Error&) {
    return false;  // unreadable or damaged: build it again
  }
}

BatchShard parse_batch_shard(const std::string& text, const std::string& what) {
  const size_t slash = text.find('/');
  BatchShard s;
  char* end = nullptr;
  bool ok = slash != std::string::npos && slash > 0;
  if (ok) {
    s.index = int(std::strtol(text.substr(0, slash).c_str(), &end, 10));
    ok = *end == '\0';
  }
  if (ok) {
    const std::string n = text.substr(slash + 1);
    s.count = int(std::strtol(n.c_str(), &end, 10));
    ok = !n.empty() && *end == '\0';
  }
  if (!ok || s.count < 1 || s.index < 0 || s.index >= s.count)
    fail(what, " '", text, "': expected i/n with 0 <= i < n (e.g. 0/4 for the first of 4 shards)");
  return s;
}

std::vector<BatchRecord> plan_batch(const std::vector<BatchShape>& shapes, const BodyModel& model,
                                    const PrecomputeOptions& options, const std::string& out_dir,
                                    const BatchShard& shard, int task_index) {
  require(task_index < int(shapes.size()), "task index ", task_index, " is past the last data row (",
          int(shapes.size()) - 1, ")");
  const std::string model_hash = body_model_hash(model);
  std::map<std::string, int> first_row;  // over the whole file, so every slice agrees
  std::vector<std::string> keys(shapes.size());
  const std::string prefix = key_prefix(model, options);
  for (const BatchShape& s : shapes) {
    if (!s.error.empty()) continue;
    keys[s.row] = key_of(prefix, s.betas);
    first_row.emplace(keys[s.row], s.row);
  }
  std::vector<BatchRecord> out;
  for (const BatchShape& s : shapes) {
    if (task_index >= 0 ? s.row != task_index : !shard.contains(s.row)) continue;
    BatchRecord r;
    r.row = s.row;
    r.line = s.line;
    r.name = s.name;
    if (!s.error.empty()) {
      r.status = "failed";
      r.error = s.error;
    } else {
      r.key = keys[s.row];
      r.file = (fs::path(out_dir) / batch_avatar_file_name(r.key)).string();
      const int first = first_row.at(r.key);
      if (first != s.row) {
        r.status = "duplicate";
        r.error = "same shape and options as row " + std::to_string(first);
      } else {
        r.status = batch_output_done(r.file, model_hash, s.betas) ? "exists" : "pending";
        if (r.status == "exists") {
          try {
            r.topology = avatar_file_topology(r.file);
          } catch (const Error&) {
            // /meta says done but the tets cannot be read: no topology to record (the folder
            // check passes such a file over).
          }
        }
      }
    }
    out.push_back(std::move(r));
  }
  return out;
}

BatchRecord precompute_batch_row(const BatchRecord& pending, const BatchShape& shape, const TemplateVolume& tv,
                                 const BodyModel& model, const PrecomputeOptions& options) {
  BatchRecord r = pending;
  Timer timer;
  const std::string mine = (fs::path(r.file).parent_path() / ("." + fs::path(r.file).filename().string() + "." +
                                                               process_tag() + ".tmp"))
                               .string();
  try {
    require(shape.error.empty(), "row ", shape.row, " is not valid: ", shape.error);
    const Avatar a = precompute_shape(tv, model, shape.betas, options);
    write_avatar(a, mine);  // itself atomic (mine.partial -> mine)
    r.topology = tet_topology_hash(a.tet.elements);
    std::error_code ec;
    fs::rename(mine, r.file, ec);
    if (ec) fail("cannot move ", mine, " to ", r.file, ": ", ec.message());
    r.status = "built";
    r.error.clear();
  } catch (const std::exception& e) {
    std::error_code ec;
    fs::remove(mine, ec);
    r.status = "failed";
    r.error = e.what();
  }
  r.seconds = timer.seconds();
  r.peak_rss_mib = peak_rss_mib();
  return r;
}

void write_batch_manifest(const std::vector<BatchRecord>& records, const std::string& path) {
  io::write_text_file(path, [&](std::ostream& f) {
    f << kManifestHeader << '\n';
    for (const BatchRecord& r : records)
      f << r.row << ',' << r.line << ',' << csv_field(r.name) << ',' << r.key << ',' << csv_field(r.file) << ','
        << r.status << ',' << r.topology << ',' << fixed(r.seconds, 3) << ',' << fixed(r.peak_rss_mib, 1) << ',' << csv_field(r.error)
        << '\n';
  });
}

std::vector<BatchRecord> read_batch_manifest(const std::string& path) {
  std::ifstream in(path);
  if (!in) fail(path, ": cannot open the manifest");
  std::string line;
  if (!std::getline(in, line)) line.clear();
  if (!line.empty() && line.back() == '\r') line.pop_back();
  const bool with_topology = line == kManifestHeader;
  if (!with_topology && line != kManifestHeaderWithoutTopology)
    fail(path, ":1: not a batch manifest (expected the header '", kManifestHeader, "')");
  const size_t fields = with_topology ? 10 : 9, t = with_topology ? 1 : 0;  // t: shift after the topology column
  std::vector<BatchRecord> out;
  int lineno = 1;
  while (std::getline(in, line)) {
    ++lineno;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) continue;
    const auto f = split_csv(line);
    if (f.size() != fields) fail(path, ":", lineno, ": expected ", fields, " fields, found ", f.size());
    BatchRecord r;
    double row = 0, ln = 0;
    if (!parse_number(f[0], &row) || !parse_number(f[1], &ln) || !parse_number(f[6 + t], &r.seconds) ||
        !parse_number(f[7 + t], &r.peak_rss_mib))
      fail(path, ":", lineno, ": row, line, seconds and peak_rss_mib must be numbers");
    r.row = int(row);
    r.line = int(ln);
    r.name = f[2];
    r.key = f[3];
    r.file = f[4];
    r.status = f[5];
    if (with_topology) r.topology = f[6];
    r.error = f[8 + t];
    r.manifest_line = lineno;
    out.push_back(std::move(r));
  }
  return out;
}

std::string avatar_file_topology(const std::string& path) {
  auto read = [&] {
    const io::Hdf5File f(path, io::Hdf5File::Mode::Read);
    if (f.has("/meta/topology_hash")) return f.read_string("/meta/topology_hash");
    if (!f.has("/tet/elements")) fail(path, ": not an avatar file (dataset /tet/elements is missing)");
    return tet_topology_hash(f.read_int_matrix("/tet/elements", -1, 4));
  };
  return io::read_in_child_first(path, read);  // a file that crashes libhdf5 is refused (io/crash_isolation.hpp)
}

void check_batch_topology(const std::string& out_dir, const std::string& expected, const std::string& expected_from) {
  std::error_code ec;
  if (!fs::is_directory(out_dir, ec)) return;
  std::vector<std::string> files;
  for (const auto& entry : fs::directory_iterator(out_dir, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("avatar-", 0) == 0 && name.size() > 3 && name.compare(name.size() - 3, 3, ".h5") == 0)
      files.push_back(entry.path().string());
  }
  std::sort(files.begin(), files.end());
  std::string first_file, first;
  for (const std::string& file : files) {
    std::string h;
    try {
      h = avatar_file_topology(file);
    } catch (const Error&) {
      continue;  // not a readable avatar (an interrupted copy, say): plan_batch has it rebuilt
    }
    if (first_file.empty()) {
      first_file = file, first = h;
    } else if (h != first) {
      fail("batch: ", first_file, " and ", file, " have different tet topologies (element array hashes ", first,
           " and ", h, "): every avatar of a batch must share one; build into an empty --out-dir");
    }
  }
  if (!expected.empty() && !first_file.empty() && first != expected)
    fail("batch: ", first_file, " has tet topology ", first, " but this run's avatars have ", expected, " (",
         expected_from, "): every avatar of a batch must share one; build into an empty --out-dir");
}

void verify_batch_manifest(const std::string& path) {
  for (const BatchRecord& r : read_batch_manifest(path)) {
    std::error_code ec;
    if (r.topology.empty() || r.file.empty() || !fs::exists(r.file, ec)) continue;
    const std::string actual = avatar_file_topology(r.file);
    if (actual != r.topology)
      fail(path, ":", r.manifest_line, ": row ", r.row, ": ", r.file, " has tet topology ", actual,
           " but the manifest records ", r.topology);
  }
}

std::string batch_summary(const std::vector<BatchRecord>& records, double wall_s) {
  std::map<std::string, int> count;
  double built_s = 0, peak = 0;
  for (const BatchRecord& r : records) {
    ++count[r.status];
    if (r.status == "built") built_s += r.seconds;
    peak = std::max(peak, r.peak_rss_mib);
  }
  std::ostringstream o;
  o << "batch summary: " << records.size() << " rows: ";
  bool sep = false;
  for (const char* s : {"built", "exists", "duplicate", "pending", "failed"}) {
    if (!count.count(s)) continue;
    o << (sep ? ", " : "") << count[s] << ' ' << s;
    sep = true;
  }
  o << "; wall " << fixed(wall_s, 1) << " s";
  if (count["built"] > 0)
    o << "; " << fixed(built_s / count["built"], 2) << " s per built shape (mean of its own time), peak memory "
      << fixed(peak, 0) << " MiB";
  o << '\n';
  if (count["failed"] > 0) {
    size_t wname = 4;
    for (const BatchRecord& r : records)
      if (r.status == "failed") wname = std::max(wname, r.name.size());
    o << "failed rows:\n  " << std::left << std::setw(6) << "row" << std::setw(6) << "line" << std::setw(int(wname) + 2)
      << "name"
      << "error\n";
    for (const BatchRecord& r : records)
      if (r.status == "failed")
        o << "  " << std::setw(6) << r.row << std::setw(6) << r.line << std::setw(int(wname) + 2) << r.name << r.error
          << '\n';
  }
  return o.str();
}

std::string batch_progress_line(int done, int total, int failed, double elapsed_s) {
  std::ostringstream o;
  o << "batch: " << done << '/' << total << " rows done";
  if (failed > 0) o << " (" << failed << " failed)";
  if (done > 0 && elapsed_s > 0) {
    const double rate = done / elapsed_s;
    o << ", " << (rate >= 1 ? fixed(rate, 2) + " rows/s" : fixed(60 * rate, 2) + " rows/min") << ", elapsed "
      << duration(elapsed_s);
    if (done < total) o << ", ETA " << duration((total - done) / rate);
  }
  return o.str();
}

}  // namespace sflsh
