// rackcat: an emulated EtherCAT modular I/O rack. See README.md.
#include <cstdio>
#include <exception>
#include <map>
#include <string>
#include <vector>

#include <rackcat_version.hpp>  // generated in the build tree by cmake/rackcat_version.cmake

#include "apps/commands.hpp"

namespace rackcat::apps {
namespace {
std::map<std::string, RegisterFn>& registry() {
  static std::map<std::string, RegisterFn> r;
  return r;
}
}  // namespace

struct ExitRequest {
  int code;
};

CommandRegistrar::CommandRegistrar(const char* name, RegisterFn fn) {
  registry()[name] = fn;
}

void register_all(CLI::App& app) {
  for (const auto& [name, fn] : registry()) fn(app);
}

void exit_with(int code) {
  throw ExitRequest{code};
}

}  // namespace rackcat::apps

int main(int argc, char** argv) {
  // Everything inside the try: building the command line can throw too (std::bad_alloc).
  try {
    CLI::App app{"rackcat: an emulated EtherCAT modular I/O rack (Fusion.IO-style MDP device)"};
    app.require_subcommand(1);
    const std::string version =
        std::string("rackcat ") + RACKCAT_VERSION + " (git " + RACKCAT_GIT_REVISION + ")";
    app.set_version_flag("--version", version, "Print the version and exit");
    rackcat::apps::register_all(app);
    // `rackcat SUBCOMMAND [SUBCOMMAND...] --version` too, at every depth (`ctl esm --version`).
    std::vector<CLI::App*> pending = app.get_subcommands([](CLI::App*) { return true; });
    while (!pending.empty()) {
      CLI::App* sub = pending.back();
      pending.pop_back();
      sub->set_version_flag("--version", version, "Print the version and exit");
      for (CLI::App* nested : sub->get_subcommands([](CLI::App*) { return true; })) {
        pending.push_back(nested);
      }
    }
    try {
      app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
      // CLI11 uses exit code 0 for --help; usage errors are 2 as documented.
      const int rc = app.exit(e);
      return rc == 0 ? 0 : 2;
    }
  } catch (const rackcat::apps::ExitRequest& r) {
    return r.code;
  } catch (const std::exception& e) {
    // Anything a subcommand did not turn into its own message: one line, never a crash.
    std::fprintf(stderr, "rackcat: %s\n", e.what());
    return 1;
  }
  return 0;
}
