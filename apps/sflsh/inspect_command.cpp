// `sflsh inspect FILE [--json]`: what an avatar file holds and its quality
// figures, or (a result file) what a simulation result holds, incomplete or not.
#include <cstdio>
#include <iostream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "command.hpp"
#include "sflsh/asset/avatar_file.hpp"
#include "sflsh/io/crash_isolation.hpp"
#include "sflsh/io/hdf5_file.hpp"
#include "sflsh/io/input_file.hpp"
#include "sflsh/precompute/avatar_summary.hpp"
#include "sflsh/scene/result_contacts.hpp"
#include "sflsh/scene/result_file.hpp"

namespace sflsh::cli {
namespace {

struct InspectArgs {
  std::string path;
  bool json = false;
};

/// A result file (it has /frames): its summary ("incomplete" when the run
/// stopped early) and its contact terms with their peak force.
bool inspect_result(const InspectArgs& args) {
  bool is_result = false;
  auto sniff = [&] {
    const io::Hdf5File f(args.path, io::Hdf5File::Mode::Read);
    return f.has("/frames") && f.has("/meta/format_version");
  };
  io::probe_in_child_process(args.path, [&] { sniff(); });  // libhdf5 may crash on a damaged file
  is_result = sniff();
  if (!is_result) return false;
  const SimulationResult r = read_simulation_result(args.path);
  if (args.json) {
    nlohmann::json contacts = nlohmann::json::array();
    for (const ContactTrack& c : r.contacts)
      contacts.push_back({{"term", c.term}, {"body", c.body}, {"peak_force", peak_contact_force(c)}});
    const nlohmann::json j = {{"file", "result"}, {"frames", r.frame_time.size()}, {"steps", r.step_time.size()},
                              {"incomplete", r.incomplete}, {"contacts", contacts}};
    std::printf("%s\n", j.dump().c_str());
  } else {
    std::printf("%s: simulation result, %d frames, %zu steps, %s\n", args.path.c_str(), int(r.frame_time.size()),
                r.step_time.size(), r.incomplete ? ("INCOMPLETE (" + r.stop_reason + ")").c_str() : "complete");
    std::fputs(describe_contacts(r).c_str(), stdout);
  }
  return true;
}

void run_inspect(const InspectArgs& args) {
  io::require_input_file(args.path, "");
  if (inspect_result(args)) return;
  const Avatar avatar = read_avatar(args.path);
  const AvatarSummary s = summarize_avatar(avatar);
  std::cout << (args.json ? s.to_json() : s.to_text(args.path));
}

const CommandRegistrar reg(30, [](CLI::App& app) {
  auto args = std::make_shared<InspectArgs>();
  auto* cmd = app.add_subcommand("inspect", "Print what an avatar file holds and its quality figures, or a result file's frames and whether it is complete");
  cmd->add_option("avatar", args->path, "Avatar HDF5 file written by `sflsh precompute`, or a result file of `sflsh simulate`")->required();
  cmd->add_flag("--json", args->json, "Machine-readable output");
  cmd->callback([args] { run_inspect(*args); });
});

}  // namespace
}  // namespace sflsh::cli
