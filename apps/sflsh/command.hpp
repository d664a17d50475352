#pragma once
// Each sub-command lives in its own file and registers itself here with an
// order key (for --help listing), so adding a command touches no other file.
#include <functional>

#include <CLI/CLI.hpp>

namespace sflsh::cli {

using CommandSetup = std::function<void(CLI::App& app)>;

struct CommandRegistrar {
  CommandRegistrar(int order, CommandSetup setup);
};

/// Adds every registered command to `app` in order.
void setup_commands(CLI::App& app);

}  // namespace sflsh::cli
