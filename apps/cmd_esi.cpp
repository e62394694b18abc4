// `rackcat esi [--config FILE] [-o FILE]` writes the ETG.2000 ESI file of the rack (with the
// ETG.5001 Slots/Modules of the whole card catalogue) to FILE or stdout.
#include <fstream>
#include <iostream>
#include <memory>
#include <string>

#include "apps/commands.hpp"
#include "apps/rack_slave/rack_loading.hpp"
#include "esi/rack.hpp"
#include "mdp/device.hpp"
#include "mdp/rack_config.hpp"

namespace rackcat::apps {
namespace {

struct EsiOptions {
  std::string config;
  std::string output;
};

int run_esi(const EsiOptions& o) {
  auto config = load_rack_or_report(o.config);
  if (!config) return 2;
  const std::unique_ptr<mdp::Device> device = offline_device(std::move(*config));
  std::string xml;
  try {
    xml = esi::write_esi(*device);
  } catch (const std::exception& e) {
    std::cerr << "rackcat esi: " << e.what() << "\n";
    return 1;
  }
  if (o.output.empty() || o.output == "-") {
    std::cout << xml;
    return std::cout ? 0 : 1;
  }
  std::ofstream out(o.output, std::ios::trunc);
  out << xml;
  out.close();
  if (!out) {
    std::cerr << "rackcat esi: cannot write " << o.output << "\n";
    return 1;
  }
  return 0;
}

void add_esi(CLI::App& app) {
  auto opts = std::make_shared<EsiOptions>();
  auto* cmd = app.add_subcommand("esi",
                                 "Write the ESI file of the rack (ETG.2000, modular "
                                 "description per ETG.5001)");
  cmd->add_option("--config", opts->config, "Rack file (YAML); default: the built-in rack");
  cmd->add_option("-o,--output", opts->output, "ESI file to write (default: stdout)");
  cmd->callback([opts] { exit_with(run_esi(*opts)); });
}

const CommandRegistrar reg{"esi", add_esi};

}  // namespace
}  // namespace rackcat::apps
