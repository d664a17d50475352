// `sflsh inspect avatar.h5 [--json]`: what an avatar file holds and its quality figures.
#include <cstdio>
#include <iostream>
#include <sstream>

#include "command.hpp"
#include "sflsh/asset/avatar_file.hpp"
#include "sflsh/precompute/avatar_summary.hpp"

namespace sflsh::cli {
namespace {

struct InspectArgs {
  std::string path;
  bool json = false;
};

void run_inspect(const InspectArgs& args) {
  const Avatar avatar = read_avatar(args.path);
  const AvatarSummary s = summarize_avatar(avatar);
  std::cout << (args.json ? s.to_json() : s.to_text(args.path));
}

const CommandRegistrar reg(30, [](CLI::App& app) {
  auto args = std::make_shared<InspectArgs>();
  auto* cmd = app.add_subcommand("inspect", "Print what an avatar file holds and its quality figures");
  cmd->add_option("avatar", args->path, "Avatar HDF5 file written by `sflsh precompute`")->required();
  cmd->add_flag("--json", args->json, "Machine-readable output");
  cmd->callback([args] { run_inspect(*args); });
});

}  // namespace
}  // namespace sflsh::cli
