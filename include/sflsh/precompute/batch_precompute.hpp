#pragma once
// Batch precompute: one avatar per row of a shapes CSV.
//   Input: one β vector per line. A first line that is not all numbers is a
//     header; a header column named "name" (any case) holds a label per row,
//     the other columns are β in order. With a header every row must have as
//     many fields as the header.
//   Output: <out-dir>/avatar-<key>.h5 per row, with <key> a content key of the
//     model, β and every option that changes the avatar (avatar_content_key),
//     so a rerun skips rows that are done and a crashed run resumes. Rows with
//     the same key share one file, computed once.
//   Manifest: one CSV line per row: row,line,name,key,file,status,topology,
//     seconds,peak_rss_mib,error (write_batch_manifest); topology is the
//     output's element array hash (mesh/tet_topology_hash.hpp).
//   One topology: every avatar in an output folder has the same tets (seed
//     §4); a folder whose files differ, or differ from what the run would
//     build, is refused (check_batch_topology), and so is a manifest whose
//     recorded topology is not its file's (verify_batch_manifest).
//   Slices: a row belongs to shard i/n when row % n == i, so the n shards of
//     a file cover every row exactly once; --task-index r runs row r alone.
#include <string>
#include <vector>

#include "sflsh/precompute/precompute.hpp"

namespace sflsh {

/// One data row of the shapes CSV.
struct BatchShape {
  int row = 0;        ///< 0-based data row (header and blank lines not counted): the task index
  int line = 0;       ///< 1-based line of the CSV file
  std::string name;   ///< the "name" column, "" when there is none
  VecX betas;         ///< the model's num_betas entries (missing ones 0); valid rows only
  std::string error;  ///< why the row cannot be built ("" = valid)
};

/// Reads every data row of `path`. A row that cannot be used (a field that is
/// not a number, NaN or infinite β, a field count unlike the header's, more β
/// than the model's `model_betas` shape directions) gets `error` set and the
/// others are still read. Throws sflsh::Error only for the file as a whole:
/// missing, no data row, or a header with two "name" columns.
std::vector<BatchShape> read_batch_shapes(const std::string& path, int model_betas);

/// 16 hex digits (FNV-1a) over the avatar format version, the model hash, the
/// template-stage cache key, β (`betas`, already padded to the model) and every
/// shape-stage option (thickness map, handles or handle positions, placement,
/// BBW and cubature options; not show_progress or cache_dir).
std::string avatar_content_key(const BodyModel& model, const VecX& betas, const PrecomputeOptions& options);

/// File name of the avatar with content key `key`: "avatar-<key>.h5".
std::string batch_avatar_file_name(const std::string& key);

/// True when `path` is an avatar file with model hash `model_hash` and β equal
/// to `betas` (bit for bit): a finished output of that row. Reads only /meta.
bool batch_output_done(const std::string& path, const std::string& model_hash, const VecX& betas);

/// A slice of the rows: shard `index` of `count`.
struct BatchShard {
  int index = 0, count = 1;
  bool contains(int row) const { return row % count == index; }
};
/// Parses "i/n" (0 <= i < n); throws naming `what` (the option) otherwise.
BatchShard parse_batch_shard(const std::string& text, const std::string& what = "--shard");

/// What happened to one row.
struct BatchRecord {
  int row = 0, line = 0;
  std::string name, key;
  std::string file;    ///< output path ("" for rows that failed before a key existed)
  /// pending (to compute), built, exists (done by an earlier run), duplicate
  /// (same key as an earlier row; `error` names it), failed.
  std::string status;
  double seconds = 0;       ///< wall time of this row's work (worker process: its whole run)
  double peak_rss_mib = 0;  ///< peak memory of the process that built it
  std::string error;        ///< the one-line reason when failed; the first row when duplicate
  /// tet_topology_hash of the output's elements (built and exists rows; "" otherwise).
  std::string topology;
  int manifest_line = 0;    ///< 1-based line in the manifest it was read from (read_batch_manifest)
};

/// The records of the rows of `shapes` in `shard` (all rows when
/// `task_index` < 0, else that row alone, which must exist): invalid rows
/// failed, rows whose key an earlier row of the file has are duplicate,
/// rows whose file is already done exist (with their file's topology), the
/// rest pending.
std::vector<BatchRecord> plan_batch(const std::vector<BatchShape>& shapes, const BodyModel& model,
                                    const PrecomputeOptions& options, const std::string& out_dir,
                                    const BatchShard& shard = {}, int task_index = -1);

/// Builds a pending row in this process (shape stage on `tv`, then the avatar
/// file, written atomically under a temporary name unique to this process and
/// renamed into place) and returns its record as built, or failed with the
/// error when the shape stage or the write throws.
BatchRecord precompute_batch_row(const BatchRecord& pending, const BatchShape& shape, const TemplateVolume& tv,
                                 const BodyModel& model, const PrecomputeOptions& options);

/// Writes `records` as CSV (header row,line,name,key,file,status,topology,
/// seconds,peak_rss_mib,error), atomically.
void write_batch_manifest(const std::vector<BatchRecord>& records, const std::string& path);
/// Reads a manifest written by write_batch_manifest (also one from before the
/// topology column: topology ""); throws naming the file and line.
std::vector<BatchRecord> read_batch_manifest(const std::string& path);

/// The tet topology of the avatar file `path`: its /meta/topology_hash, or for
/// files written before that dataset, tet_topology_hash of /tet/elements.
/// Throws naming the file when it cannot be read.
std::string avatar_file_topology(const std::string& path);

/// Refuses (throws one line naming both files) an `out_dir` whose
/// avatar-*.h5 files do not all have the same tet topology, and (naming the
/// file and `expected_from`) one whose files differ from `expected` (the
/// topology this run builds; "" = not checked). Files that are not readable
/// avatars are passed over (a batch rebuilds them). A missing folder passes.
void check_batch_topology(const std::string& out_dir, const std::string& expected = "",
                          const std::string& expected_from = "");

/// Refuses (throws one line naming the manifest line, the row and the file) a
/// manifest with a row whose recorded topology is not that of its file (rows
/// without a recorded topology or without a file on disk are not checked).
void verify_batch_manifest(const std::string& path);

/// Counts per status, time, per-shape mean, largest peak memory and a table
/// of the failed rows (row, line, name, error). `wall_s` is the batch's wall time.
std::string batch_summary(const std::vector<BatchRecord>& records, double wall_s);

/// "batch: 5/16 rows done (1 failed), 18.75 rows/min, elapsed 16 s, ETA 35 s"
/// (rows/s from 1 row/s up):
/// `done` of the `total` rows to compute are finished (`failed` of them
/// failed) after `elapsed_s` seconds; the ETA assumes the same rate.
std::string batch_progress_line(int done, int total, int failed, double elapsed_s);

}  // namespace sflsh
