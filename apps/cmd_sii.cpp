// `rackcat sii [--config FILE] -o FILE` writes the SII EEPROM image the emulated slave serves;
// `rackcat sii --dump FILE` prints an image in readable form (ETG.2010 words and categories).
#include <cstdio>
#include <fstream>
#include <iostream>
#include <iterator>
#include <memory>
#include <string>

#include "apps/commands.hpp"
#include "apps/rack_slave/rack_loading.hpp"
#include "esi/rack.hpp"
#include "esi/sii_parser.hpp"
#include "mdp/device.hpp"
#include "mdp/rack_config.hpp"

namespace rackcat::apps {
namespace {

struct SiiOptions {
  std::string config;
  std::string output;
  std::string dump;
};

int dump_image(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    std::cerr << "rackcat sii: cannot read " << path << "\n";
    return 1;
  }
  std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)),
                             std::istreambuf_iterator<char>());
  try {
    std::cout << esi::format_sii(esi::parse_sii(bytes));
  } catch (const esi::SiiParseError& e) {
    std::cerr << path << ": invalid SII image: " << e.what() << "\n";
    return 1;
  }
  return 0;
}

int write_image(const SiiOptions& o) {
  auto config = load_rack_or_report(o.config);
  if (!config) return 2;
  const std::unique_ptr<mdp::Device> device = offline_device(std::move(*config));
  esi::SiiImage image;
  try {
    image = esi::build_sii(*device);
  } catch (const std::exception& e) {
    std::cerr << "rackcat sii: " << e.what() << "\n";
    return 1;
  }
  std::ofstream out(o.output, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(image.bytes.data()),
            static_cast<std::streamsize>(image.bytes.size()));
  out.close();
  if (!out) {
    std::cerr << "rackcat sii: cannot write " << o.output << "\n";
    return 1;
  }
  return 0;
}

void add_sii(CLI::App& app) {
  auto opts = std::make_shared<SiiOptions>();
  auto* cmd = app.add_subcommand("sii",
                                 "Write the SII EEPROM image of the rack (ETG.2010), or "
                                 "dump an image in readable form");
  cmd->add_option("--config", opts->config, "Rack file (YAML); default: the built-in rack");
  auto* out = cmd->add_option("-o,--output", opts->output, "Image file to write");
  auto* dump = cmd->add_option("--dump", opts->dump, "Print this image file readably");
  dump->excludes(out);
  dump->excludes(cmd->get_option("--config"));
  cmd->callback([opts] {
    if (!opts->dump.empty()) exit_with(dump_image(opts->dump));
    if (opts->output.empty()) {
      std::cerr << "rackcat sii: -o FILE (or --dump FILE) is required\n";
      exit_with(2);
    }
    exit_with(write_image(*opts));
  });
}

const CommandRegistrar reg{"sii", add_sii};

}  // namespace
}  // namespace rackcat::apps
