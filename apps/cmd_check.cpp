// `rackcat check FILE`: validates a rack file the way every other subcommand does
// (apps/rack_slave/rack_loading.hpp: parse, then build the device and its drivers offline) and
// prints the device it describes: identity, RIMs with their slot cards and module numbers, the
// default process data and the size of the object dictionary. A bad file is one line "FILE:LINE:
// problem" and exit code 2; a good one exits 0.
//
// `rackcat check --line FILE` and `rackcat check --eni FILE --esi-dir DIR` validate a line the
// way `rackcat run` loads it (apps/line/line_loading.hpp: the same function) and print one line
// per slave: position, identity, name and process-data sizes, and the wiring.
#include <cstdio>
#include <string>

#include "apps/commands.hpp"
#include "apps/line/line_loading.hpp"
#include "apps/pdo_layout.hpp"
#include "apps/rack_slave/rack_loading.hpp"
#include "device/generic_device.hpp"
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

int run_check_line(const LineSource& source) {
  auto line = load_line_or_report(source);
  if (!line) return 2;
  std::printf("%s: ok, %zu slave(s)\n", line->file.c_str(), line->devices.size());
  for (size_t i = 0; i < line->devices.size(); ++i) {
    const auto& d = line->devices[i];
    if (d.rack) {
      const auto device = offline_device(*d.rack);
      std::printf(
          "slave %zu: rack %s vendor 0x%08X product 0x%08X revision 0x%08X, %u output "
          "byte(s), %u input byte(s)\n",
          i, d.rack->source.c_str(), d.rack->control.vendor_id, d.rack->control.product_code,
          d.rack->control.revision, device->output_bytes(), device->input_bytes());
      continue;
    }
    const auto& desc = d.esi->description;
    const device::GenericDevice g(*d.esi);
    const auto sizes = g.process_data_sizes();
    std::printf(
        "slave %zu: %s '%s' vendor 0x%08X product 0x%08X revision 0x%08X serial %u alias "
        "%u%s, %u output byte(s), %u input byte(s)%s%s\n",
        i, desc.order_code.c_str(), desc.device_name.c_str(), desc.vendor_id, desc.product_code,
        desc.revision, desc.serial, desc.config.station_alias, d.esi->has_coe ? ", CoE" : "",
        sizes.outputs, sizes.inputs, d.name.empty() ? "" : ", name ", d.name.c_str());
  }
  for (const auto& w : line->wiring) {
    std::printf("wire: slave %zu outputs bits %zu..%zu -> slave %zu inputs bits %zu..%zu\n", w.from,
                w.from_bit, w.from_bit + w.bits - 1, w.to, w.to_bit, w.to_bit + w.bits - 1);
  }
  return 0;
}

void add_check(CLI::App& app) {
  auto file = std::make_shared<std::string>();
  auto line = std::make_shared<LineSource>();
  auto* cmd = app.add_subcommand(
      "check",
      "Validate a rack file, a line file or an ENI as every subcommand does and print what it "
      "describes");
  auto* rack = cmd->add_option("FILE", *file, "rack file (YAML)");
  auto* line_opt = cmd->add_option("--line", line->line, "line file (YAML, docs/LINE.md)");
  auto* eni = cmd->add_option("--eni", line->eni, "ENI file (ETG.2100)");
  auto* esi_dir =
      cmd->add_option("--esi-dir", line->esi_dir, "directory of the ENI's ESI and rack files");
  eni->needs(esi_dir);
  esi_dir->needs(eni);
  rack->excludes(line_opt);
  rack->excludes(eni);
  line_opt->excludes(eni);
  cmd->callback([file, line] {
    if (!line->line.empty() || !line->eni.empty()) exit_with(run_check_line(*line));
    if (file->empty()) {
      std::fprintf(stderr, "rackcat check: name a rack FILE, --line FILE or --eni FILE\n");
      exit_with(2);
    }
    exit_with(run_check(*file));
  });
}

const CommandRegistrar reg{"check", add_check};

}  // namespace
}  // namespace rackcat::apps
