// `rackcat firmware pack` builds a firmware container (mdp/firmware_image.hpp, docs/FOE.md) a
// master writes over FoE in BOOT; `rackcat firmware check FILE` verifies one against the rack.
#include <cstdio>
#include <fstream>
#include <iostream>
#include <iterator>
#include <memory>
#include <string>
#include <vector>

#include "apps/commands.hpp"
#include "apps/rack_slave/rack_loading.hpp"
#include "mdp/firmware_image.hpp"
#include "mdp/rack_config.hpp"

namespace rackcat::apps {
namespace {

struct FirmwareOptions {
  std::string config;
  std::string output;
  std::string payload;
  std::string software_version;
  std::string short_version;
  uint32_t revision = 0;
  std::string check;
};

bool read_all(const std::string& path, std::vector<uint8_t>& out) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  out.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  return !in.bad();
}

int pack(const FirmwareOptions& o) {
  auto config = load_rack_or_report(o.config);
  if (!config) return 2;
  std::vector<uint8_t> payload;
  if (!o.payload.empty() && !read_all(o.payload, payload)) {
    std::cerr << "rackcat firmware: cannot read " << o.payload << "\n";
    return 1;
  }
  const mdp::FirmwareInfo info{config->control.vendor_id, config->control.product_code, o.revision,
                               o.software_version, o.short_version};
  std::string error;
  const auto file = mdp::pack_firmware(info, payload, error);
  if (!file) {
    std::cerr << "rackcat firmware: " << error << "\n";
    return 2;
  }
  std::ofstream out(o.output, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(file->data()),
            static_cast<std::streamsize>(file->size()));
  out.close();
  if (!out) {
    std::cerr << "rackcat firmware: cannot write " << o.output << "\n";
    return 1;
  }
  return 0;
}

int check(const FirmwareOptions& o) {
  auto config = load_rack_or_report(o.config);
  if (!config) return 2;
  std::vector<uint8_t> file;
  if (!read_all(o.check, file)) {
    std::cerr << "rackcat firmware: cannot read " << o.check << "\n";
    return 1;
  }
  mdp::FirmwareInfo info;
  std::string detail;
  const auto e = mdp::verify_firmware(file, config->control.vendor_id, config->control.product_code,
                                      info, detail);
  if (e != foe::FoeError::None) {
    std::fprintf(stderr, "%s: refused, FoE error 0x%04X (%s): %s\n", o.check.c_str(),
                 static_cast<unsigned>(e), std::string(foe::describe(e)).c_str(), detail.c_str());
    return 1;
  }
  std::printf("%s: firmware %s, short version '%s', revision 0x%08X, %zu payload bytes\n",
              o.check.c_str(), info.software_version.c_str(), info.short_version.c_str(),
              info.revision, file.size() - mdp::kFirmwareHeaderSize);
  return 0;
}

void add_firmware(CLI::App& app) {
  auto opts = std::make_shared<FirmwareOptions>();
  auto* cmd =
      app.add_subcommand("firmware", "Build or check a firmware file for FoE (docs/FOE.md)");
  cmd->require_subcommand(1);
  auto* p = cmd->add_subcommand("pack", "Build a firmware container for the rack's product");
  p->add_option("--config", opts->config, "Rack file (YAML); default: the built-in rack");
  p->add_option("--software-version", opts->software_version,
                "0x100A text after the update (at most 23 characters)")
      ->required();
  p->add_option("--short-version", opts->short_version,
                "0x2000:02 FW Version after the update (at most 4 characters)");
  p->add_option("--revision", opts->revision,
                "0x1018:03 and SII revision after the update (UINT32)")
      ->required();
  p->add_option("--payload", opts->payload, "the firmware image proper (any bytes; default none)");
  p->add_option("-o,--output", opts->output, "container file to write")->required();
  p->callback([opts] { exit_with(pack(*opts)); });
  auto* c = cmd->add_subcommand("check", "Verify a firmware container against the rack");
  c->add_option("--config", opts->config, "Rack file (YAML); default: the built-in rack");
  c->add_option("file", opts->check, "container file")->required();
  c->callback([opts] { exit_with(check(*opts)); });
}

const CommandRegistrar reg{"firmware", add_firmware};

}  // namespace
}  // namespace rackcat::apps
