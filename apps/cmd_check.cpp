// `rackcat check FILE`: validates a rack file the way every other subcommand does
// (apps/rack_slave/rack_loading.hpp: parse, then build the device and its drivers offline) and
// prints the device it describes: identity, RIMs with their slot cards and module numbers, the
// default process data and the size of the object dictionary. A bad file is one line "FILE:LINE:
// problem" and exit code 2; a good one exits 0.
#include <cstdio>
#include <string>

#include "apps/commands.hpp"
#include "apps/pdo_layout.hpp"
#include "apps/rack_slave/rack_loading.hpp"
#include "mdp/rack_config.hpp"

namespace rackcat::apps {
namespace {

int run_check(const std::string& file) {
  auto config = load_rack_or_report(file);
  if (!config) return 2;
  const auto device = offline_device(std::move(*config));
  const mdp::RackConfig& cfg = device->config();
  const coe::ObjectDictionary& od = device->dictionary();
  const coe::Object* name = od.find(0x1008);
  std::printf("%s: ok\n", cfg.source.c_str());
  std::printf("device: '%s' vendor 0x%08X product 0x%08X revision 0x%08X serial %u\n",
              name ? name->get_string(0).c_str() : "", cfg.control.vendor_id,
              cfg.control.product_code, cfg.control.revision, cfg.control.serial);
  std::printf("control module: %s, Detect Modules Override %d\n", cfg.control.part_number.c_str(),
              cfg.detect_modules_override ? 1 : 0);
  for (const mdp::Rim& rim : cfg.rims) {
    size_t count = 0;
    for (const mdp::Module& m : cfg.modules) count += m.rim == rim.number ? 1 : 0;
    std::printf("RIM %u: %s, %zu slot card(s)\n", rim.number,
                std::string(mdp::rim_type_name(rim.type)).c_str(), count);
    for (const mdp::Module& m : cfg.modules) {
      if (m.rim != rim.number) continue;
      std::printf("  slot %2u  module %3u  %-10s ident 0x%08X  %2u channel(s)  %s\n", m.slot,
                  m.number, std::string(m.card->name).c_str(), m.card->module_ident,
                  m.card->channels, std::string(m.card->description).c_str());
    }
  }
  const PdoLayout layout = pdo_layout(od);
  size_t out_entries = 0;
  for (const auto& e : layout.entries) out_entries += e.output ? 1 : 0;
  std::printf(
      "process data (default assignment): %u output byte(s) in %zu entries, %u input byte(s) "
      "in %zu entries (`rackcat od --layout` for each offset)\n",
      device->output_bytes(), out_entries, device->input_bytes(),
      layout.entries.size() - out_entries);
  std::printf("object dictionary: %zu objects\n", od.size());
  return 0;
}

void add_check(CLI::App& app) {
  auto file = std::make_shared<std::string>();
  auto* cmd = app.add_subcommand(
      "check", "Validate a rack file as every subcommand does and print the device it describes");
  cmd->add_option("FILE", *file, "rack file (YAML)")->required();
  cmd->callback([file] { exit_with(run_check(*file)); });
}

const CommandRegistrar reg{"check", add_check};

}  // namespace
}  // namespace rackcat::apps
