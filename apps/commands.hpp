// Subcommands of the rackcat CLI. Each lives in its own apps/cmd_<name>.cpp and registers
// itself with a file-scope registrar, so adding a subcommand touches one file:
//
//   namespace { void add_od(CLI::App& app) { auto* cmd = app.add_subcommand("od", "..."); ... }
//               const rackcat::apps::CommandRegistrar reg{"od", add_od}; }
//
// A subcommand callback returns its exit code through rackcat::apps::exit_with(code)
// (0 ok, 1 runtime failure, 2 usage/configuration error).
#pragma once

#include <CLI/CLI.hpp>

namespace rackcat::apps {

using RegisterFn = void (*)(CLI::App&);

struct CommandRegistrar {
  CommandRegistrar(const char* name, RegisterFn fn);
};

// Registered subcommands in name order.
void register_all(CLI::App& app);

// Ends a subcommand with an exit code: main() returns it.
[[noreturn]] void exit_with(int code);

}  // namespace rackcat::apps
