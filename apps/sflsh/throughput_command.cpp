// `sflsh bench-throughput`: avatar-steps per second for a batch of independent
// avatars on 1, 2, ... threads (bench/throughput.hpp).
#include <cstdio>
#include <filesystem>
#include <sstream>

#include "command.hpp"
#include "sflsh/asset/avatar_file.hpp"
#include "sflsh/bench/throughput.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/core/time_step.hpp"
#include "sflsh/io/atomic_output.hpp"

namespace sflsh::cli {
namespace {

struct ThroughputArgs {
  std::string avatar, motion = "builtin:jump", dt = "1/60", avatars = "1,4,16", threads = "1,2", out = "throughput";
  long steps = 120;
};

/// "1,4,16" -> {1, 4, 16}; `option` names the flag in the error.
std::vector<int> parse_int_list(const std::string& text, const char* option) {
  std::vector<int> v;
  std::stringstream s(text);
  std::string item;
  while (std::getline(s, item, ',')) {
    size_t used = 0;
    int x = 0;
    try {
      x = std::stoi(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    require(used > 0 && used == item.size(), option, " '", text, "': '", item,
            "' is not an integer (expected a comma-separated list such as 1,4,16)");
    v.push_back(x);
  }
  require(!v.empty(), option, " is empty (expected a comma-separated list such as 1,4,16)");
  return v;
}

void run_throughput_command(const ThroughputArgs& a) {
  ThroughputOptions o;
  o.motion = a.motion;
  o.dt = parse_time_step(a.dt);
  o.steps = a.steps;
  o.avatars = parse_int_list(a.avatars, "--avatars");
  o.threads = parse_int_list(a.threads, "--threads");
  io::check_output_folder(a.out, "--out");
  const auto avatar = std::make_shared<const Avatar>(read_avatar(a.avatar));
  const ThroughputReport r = run_throughput(avatar, o);
  std::error_code ec;
  std::filesystem::create_directories(a.out, ec);
  if (ec) fail("--out ", a.out, ": cannot create output folder: ", ec.message());
  const std::string csv = (std::filesystem::path(a.out) / "throughput.csv").string();
  const std::string md = (std::filesystem::path(a.out) / "throughput.md").string();
  write_throughput_csv(r, csv);
  write_throughput_markdown(r, o, a.avatar, md);
  std::printf("%swrote %s and %s\n", r.describe().c_str(), csv.c_str(), md.c_str());
}

const CommandRegistrar reg(56, [](CLI::App& app) {
  auto a = std::make_shared<ThroughputArgs>();
  auto* cmd = app.add_subcommand("bench-throughput",
                                 "Avatar-steps per second for a batch of independent avatars on 1, 2, ... threads");
  cmd->add_option("--avatar", a->avatar, "Avatar file from `sflsh precompute`")->required();
  cmd->add_option("--motion", a->motion, "Motion driving every avatar (each at its own phase)")->capture_default_str();
  cmd->add_option("--dt", a->dt, "Time step in seconds (e.g. 1/60)")->capture_default_str();
  cmd->add_option("--avatars", a->avatars, "Batch sizes, comma-separated")->capture_default_str();
  cmd->add_option("--threads", a->threads, "Thread counts, comma-separated")->capture_default_str();
  cmd->add_option("--steps", a->steps, "Timed steps per batch size and thread count")->capture_default_str();
  cmd->add_option("--out", a->out, "Output folder (throughput.csv, throughput.md)")->capture_default_str();
  cmd->callback([a] { run_throughput_command(*a); });
});

}  // namespace
}  // namespace sflsh::cli
