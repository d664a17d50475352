#pragma once
// Observed skin motion for `sflsh fit`: a file in the result-file
// layout (scene/result_file.hpp: /frames/time (Fr,), /frames/positions
// (Fr,V,3), optional /meta/motion, /meta/dt, /meta/bones, and the run's own
// bones /meta/start_bones and /steps/bones) or a PC2 point cache
// (frames only; their times are i / fps). Vertices in the avatar surface's order.
#include <string>
#include <vector>

#include "sflsh/core/types.hpp"
#include "sflsh/sim/configuration.hpp"

namespace sflsh {

struct Observations {
  std::string path;
  std::vector<double> time;       ///< s, strictly increasing, ≥ 0
  std::vector<Points> positions;  ///< per frame: #V by 3 world positions (m)
  std::string motion;             ///< /meta/motion when the file has it (else empty)
  double dt = 0;                  ///< /meta/dt (s) when present, else 0
  std::string bones;              ///< /meta/bones ("kinematic" | "dynamic") when present
  /// The observed run's own bones when the file has them (a one-body result's
  /// /meta/start_bones and /steps/bones): start_bones[0] at t = −h, [1] at 0,
  /// step_bones[s] (24 each) at the end of step s + 1. Empty otherwise.
  std::vector<std::vector<Isometry>> start_bones, step_bones;
};

/// Reads `path` (.h5/.hdf5: result layout; .pc2: point cache at `pc2_fps`
/// frames per second). Throws one line naming the file and what is wrong:
/// missing datasets, shapes, frame times not strictly increasing or negative,
/// non-finite positions (naming the frame and vertex), bones that are not
/// rigid poses (naming the dataset, step and bone).
Observations read_observations(const std::string& path, double pc2_fps = 30.0);

/// Throws unless every frame has `num_vertices` rows (the avatar's surface).
void check_observation_vertices(const Observations& obs, int num_vertices, const std::string& avatar_path);

/// The simulation step of each observed time, t = s·h: throws naming the
/// frame when a time is not a whole number of steps (within 1e-6 h).
std::vector<int> observation_steps(const Observations& obs, double h);

/// Adds N(0, sigma²) noise (m) to every coordinate, seeded (reproducible).
void add_gaussian_noise(Observations& obs, double sigma, unsigned seed);

}  // namespace sflsh
