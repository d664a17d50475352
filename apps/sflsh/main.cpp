// sflsh: soft-flesh human avatars. Sub-commands register themselves
// (command.hpp); this file parses, dispatches and turns errors into one line
// on stderr and a non-zero exit.
#include <cstdio>
#include <map>
#include <vector>

#include "command.hpp"
#include "sflsh/core/error.hpp"
#include "sflsh/core/interrupt.hpp"
#include "sflsh/core/progress.hpp"

namespace sflsh::cli {
namespace {
std::multimap<int, CommandSetup>& registry() {
  static std::multimap<int, CommandSetup> r;
  return r;
}
}  // namespace

CommandRegistrar::CommandRegistrar(int order, CommandSetup setup) { registry().emplace(order, std::move(setup)); }

void setup_commands(CLI::App& app) {
  for (auto& [order, setup] : registry()) setup(app);
}

}  // namespace sflsh::cli

int main(int argc, char** argv) {
  CLI::App app{"sflsh: soft-flesh human avatars (SMPL-format bodies, reduced soft-tissue simulation)"};
  app.require_subcommand(1);
  app.add_flag_callback("-q,--quiet", [] { sflsh::Progress::set_quiet(true); }, "Print no progress");
  app.set_version_flag("--version", std::string("sflsh ") + "0.1.0");
  sflsh::cli::setup_commands(app);
  // A parse error is one line, like every other error (CLI11's default adds a
  // second "Run with --help" line).
  app.failure_message([](const CLI::App*, const CLI::Error& e) {
    return std::string("sflsh: error: ") + e.what() + " (see --help)\n";
  });
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const sflsh::Interrupted& e) {
    std::fprintf(stderr, "sflsh: %s\n", e.what());
    return e.exit_code();
  } catch (const sflsh::Error& e) {
    std::fprintf(stderr, "sflsh: error: %s\n", e.what());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "sflsh: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
