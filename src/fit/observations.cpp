#include "sflsh/fit/observations.hpp"

#include <cmath>
#include <filesystem>
#include <random>

#include "sflsh/core/error.hpp"
#include "sflsh/io/atomic_output.hpp"
#include "sflsh/io/hdf5_file.hpp"
#include "sflsh/io/crash_isolation.hpp"
#include "sflsh/io/point_cache.hpp"
#include "sflsh/scene/result_file.hpp"

namespace sflsh {

/// /meta/start_bones (2, 24, 7) and /steps/bones (S, 24, 7) of a one-body result (result_file.hpp), when present.
static void read_run_bones(const io::Hdf5File& f, const std::string& path, Observations& obs) {
  if (!f.has("/steps/bones") && !f.has("/meta/start_bones")) return;
  require(f.has("/steps/bones") && f.has("/meta/start_bones"), path,
          ": has only one of /steps/bones and /meta/start_bones (the run's bones need both)");
  const std::vector<std::int64_t> shape = f.shape("/steps/bones");
  require(shape.size() == 3 && shape[2] == 7, path, ": /steps/bones must be (steps, bones, 7)");
  if (shape[1] != 24) return;  // several bodies: not one avatar's observations (the vertex count check says so)
  obs.start_bones = read_result_poses(f, path, "/meta/start_bones", 2, 24);
  obs.step_bones = read_result_poses(f, path, "/steps/bones", shape[0], 24);
}

static Observations read_observations_in_this_process(const std::string& path, double pc2_fps) {
  require(std::filesystem::exists(path), path, ": observed file not found");
  Observations obs;
  obs.path = path;
  const std::string ext = io::lower_extension(path);
  if (ext == ".pc2") {
    require(std::isfinite(pc2_fps) && pc2_fps > 0, "--fps must be positive for a PC2 file, got ", pc2_fps);
    const io::PointCache pc = io::read_pc2(path);
    for (size_t i = 0; i < pc.frames.size(); ++i) {
      obs.time.push_back((pc.start_frame + double(i) * pc.sample_rate) / pc2_fps);
      obs.positions.push_back(pc.frames[i]);
    }
  } else {
    io::Hdf5File f(path, io::Hdf5File::Mode::Read);
    require(f.has("/frames/time") && f.has("/frames/positions"), path,
            ": expected /frames/time and /frames/positions (the result-file layout) or a .pc2 file");
    const std::vector<std::int64_t> shape = f.shape("/frames/positions");
    require(shape.size() == 3 && shape[2] == 3, path, ": /frames/positions must be (frames, vertices, 3)");
    const MatXr t = f.read_matrix("/frames/time");
    require(t.size() == shape[0], path, ": /frames/time has ", t.size(), " entries, /frames/positions ", shape[0],
            " frames");
    const long V = shape[1];
    std::vector<double> x;
    try {
      x = f.read_nd("/frames/positions", shape);
    } catch (const Error& e) {
      // Name the frame and vertex of a non-finite value (read_nd gives its flat index).
      const std::string m = e.what(), key = "non-finite value at flat index ";
      const size_t at = m.find(key);
      if (at == std::string::npos) throw;
      const long i = std::stol(m.substr(at + key.size()));
      fail(path, ": /frames/positions frame ", i / (3 * V), ": vertex ", (i / 3) % V,
           " has a non-finite position (NaN or inf)");
    }
    for (long i = 0; i < shape[0]; ++i) {
      obs.time.push_back(t.data()[i]);
      Points P(V, 3);
      for (long v = 0; v < V; ++v)
        for (int c = 0; c < 3; ++c) P(v, c) = x[(i * V + v) * 3 + c];
      obs.positions.push_back(std::move(P));
    }
    if (f.has("/meta/motion")) obs.motion = f.read_string("/meta/motion");
    if (f.has("/meta/dt")) obs.dt = f.read_scalar("/meta/dt");
    if (f.has("/meta/bones")) obs.bones = f.read_string("/meta/bones");
    read_run_bones(f, path, obs);
  }
  require(!obs.time.empty(), path, ": no frames");
  for (size_t i = 0; i < obs.time.size(); ++i) {
    require(std::isfinite(obs.time[i]) && obs.time[i] >= 0, path, ": frame ", i, " has time ", obs.time[i],
            " s, expected finite and >= 0");
    require(i == 0 || obs.time[i] > obs.time[i - 1], path, ": frame times not increasing: frame ", i, " at ",
            obs.time[i], " s after frame ", i - 1, " at ", obs.time[i - 1], " s");
    const Points& P = obs.positions[i];
    require(P.rows() == obs.positions[0].rows(), path, ": frame ", i, " has ", P.rows(), " vertices, frame 0 has ",
            obs.positions[0].rows());
    if (!P.allFinite())
      for (long v = 0; v < P.rows(); ++v)
        require(P.row(v).allFinite(), path, ": frame ", i, " (t = ", obs.time[i], " s): vertex ", v,
                " has a non-finite position (NaN or inf)");
  }
  return obs;
}

void check_observation_vertices(const Observations& obs, int num_vertices, const std::string& avatar_path) {
  require(obs.positions[0].rows() == num_vertices, obs.path, ": ", obs.positions[0].rows(),
          " vertices per frame, but the avatar ", avatar_path, " has ", num_vertices,
          " surface vertices (the observations must use its vertex order)");
}

std::vector<int> observation_steps(const Observations& obs, double h) {
  std::vector<int> steps;
  for (size_t i = 0; i < obs.time.size(); ++i) {
    const double s = obs.time[i] / h;
    require(std::abs(s - std::round(s)) <= 1e-6, obs.path, ": frame ", i, " at t = ", obs.time[i],
            " s is not a whole number of time steps of ", h, " s (give --dt to match the observations)");
    steps.push_back(int(std::lround(s)));
  }
  return steps;
}

void add_gaussian_noise(Observations& obs, double sigma, unsigned seed) {
  require(std::isfinite(sigma) && sigma >= 0, "noise sigma must be >= 0 m, got ", sigma);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n(0.0, sigma);
  for (Points& P : obs.positions)
    for (long i = 0; i < P.size(); ++i) P.data()[i] += n(rng);
}

Observations read_observations(const std::string& path, double pc2_fps) {
  // A file on which libhdf5 itself crashes is refused, not read (io/crash_isolation.hpp).
  return io::read_in_child_first(path, [&] { return read_observations_in_this_process(path, pc2_fps); });
}

}  // namespace sflsh
