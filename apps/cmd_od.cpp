// `rackcat od [--config FILE] [--format text|json] [--state-dir DIR] [--layout]`: prints the
// whole object dictionary of the rack (index, subindex, name, type, bit size, access, PDO
// mapping, value), with stored parameters applied as the running device would load them.
// --layout prints instead where each PDO entry of the current assignment sits in the master's
// process image: byte and bit offset (apps/pdo_layout.hpp).
#include <fmt/format.h>

#include <cstdio>
#include <cstring>
#include <iostream>
#include <nlohmann/json.hpp>
#include <string>

#include "apps/commands.hpp"
#include "apps/pdo_layout.hpp"
#include "apps/rack_slave/rack_loading.hpp"
#include "coe/data_type.hpp"
#include "coe/object_dictionary.hpp"
#include "mdp/device.hpp"
#include "mdp/rack_config.hpp"

namespace rackcat::apps {
namespace {

using coe::access::kRxPdoMappable;
using coe::access::kTxPdoMappable;

struct OdOptions {
  std::string config;
  std::string format = "text";
  std::string state_dir;
  bool layout = false;
};

std::string type_name(const coe::ObjectDictionary& od, const coe::Entry& e) {
  if (e.padding) return fmt::format("PAD{}", e.bit_length);
  if (coe::is_enum_type(e.data_type)) {
    if (const auto* en = od.find_enum(e.data_type)) return en->name;
    return fmt::format("ENUM 0x{:04X}", e.data_type);
  }
  const auto t = e.type();
  if (coe::is_string(t)) return fmt::format("{}({})", coe::type_name(t), e.bit_length / 8);
  return std::string(coe::type_name(t));
}

// The guide's access notation where one fits, else the per-state letters.
std::string access_text(uint16_t a) {
  using namespace coe::access;
  const uint16_t rw = a & (kReadAll | kWriteAll);
  if (rw == kRo) return "ro";
  if (rw == kRw) return "rw";
  if (rw == kRoWrPreOp) return "ro,wr_preop";
  if (rw == kRoWrOp) return "ro,wr_op";
  if (rw == kWo) return "wo";
  if (rw == 0) return "-";
  std::string s;
  s += (a & kReadPreOp) ? 'r' : '-';
  s += (a & kReadSafeOp) ? 'r' : '-';
  s += (a & kReadOp) ? 'r' : '-';
  s += (a & kWritePreOp) ? 'w' : '-';
  s += (a & kWriteSafeOp) ? 'w' : '-';
  s += (a & kWriteOp) ? 'w' : '-';
  return s;
}

std::string pdo_text(uint16_t a) {
  const bool rx = a & kRxPdoMappable;
  const bool tx = a & kTxPdoMappable;
  return rx && tx ? "rx,tx" : rx ? "rx" : tx ? "tx" : "";
}

std::string value_text(const coe::ObjectDictionary& od, const coe::Object& o, const coe::Entry& e) {
  if (e.padding) return "";
  const auto t = e.type();
  if (t == coe::DataType::VisibleString) return "\"" + o.get_string(e.subindex) + "\"";
  if (t == coe::DataType::OctetString || e.bit_length > 64) {
    std::string s;
    for (uint8_t b : o.bytes(e.subindex)) s += fmt::format("{:02x}", b);
    return s;
  }
  if (t == coe::DataType::Real32) {
    const uint32_t raw = static_cast<uint32_t>(o.get_u(e.subindex));
    float f;
    std::memcpy(&f, &raw, sizeof f);
    return fmt::format("{}", f);
  }
  if (t == coe::DataType::Real64) {
    const uint64_t raw = o.get_u(e.subindex);
    double d;
    std::memcpy(&d, &raw, sizeof d);
    return fmt::format("{}", d);
  }
  if (coe::is_enum_type(e.data_type)) {
    const uint64_t v = o.get_u(e.subindex);
    if (const auto* en = od.find_enum(e.data_type)) {
      for (const auto& ev : en->values) {
        if (ev.value == static_cast<int64_t>(v)) return fmt::format("{} ({})", v, ev.name);
      }
    }
    return fmt::format("{}", v);
  }
  if (coe::is_signed(t)) return fmt::format("{}", o.get_i(e.subindex));
  const uint64_t v = o.get_u(e.subindex);
  const unsigned digits = (e.bit_length + 3) / 4;
  return e.bit_length >= 8 ? fmt::format("0x{:0{}X}", v, digits) : fmt::format("{}", v);
}

std::string_view code_name(coe::ObjectCode c) {
  switch (c) {
    case coe::ObjectCode::Var:
      return "VAR";
    case coe::ObjectCode::Array:
      return "ARRAY";
    case coe::ObjectCode::Record:
      return "RECORD";
  }
  return "?";
}

void print_text(coe::ObjectDictionary& od) {
  std::printf("%-6s %-4s %-44s %-18s %5s %-11s %-5s %s\n", "index", "sub", "name", "type", "bits",
              "access", "pdo", "value");
  od.for_each([&](coe::Object& o) {
    if (o.hooks().before_read) o.hooks().before_read(o, -1);
    if (o.code() != coe::ObjectCode::Var) {
      std::printf("0x%04X      %-44s %-18s %5zu\n", o.index(), o.name().c_str(),
                  std::string(code_name(o.code())).c_str(), o.bit_size());
    }
    for (const auto& e : o.entries()) {
      const std::string name = o.code() == coe::ObjectCode::Var ? o.name() : e.name;
      std::printf("0x%04X %-4s %-44s %-18s %5u %-11s %-5s %s\n", o.index(),
                  fmt::format("{:02X}", e.subindex).c_str(), name.c_str(), type_name(od, e).c_str(),
                  e.bit_length, access_text(e.access).c_str(), pdo_text(e.access).c_str(),
                  value_text(od, o, e).c_str());
    }
  });
}

void print_json(coe::ObjectDictionary& od) {
  nlohmann::json objects = nlohmann::json::array();
  od.for_each([&](coe::Object& o) {
    if (o.hooks().before_read) o.hooks().before_read(o, -1);
    nlohmann::json entries = nlohmann::json::array();
    for (const auto& e : o.entries()) {
      entries.push_back({{"subindex", e.subindex},
                         {"name", e.name},
                         {"type", type_name(od, e)},
                         {"data_type", e.data_type},
                         {"bit_size", e.bit_length},
                         {"bit_offset", e.bit_offset},
                         {"access", access_text(e.access)},
                         {"access_bits", e.access},
                         {"pdo", pdo_text(e.access)},
                         {"padding", e.padding},
                         {"unit", e.unit ? fmt::format("0x{:08X}", e.unit) : std::string()},
                         {"value", value_text(od, o, e)}});
    }
    objects.push_back({{"index", fmt::format("0x{:04X}", o.index())},
                       {"name", o.name()},
                       {"object_code", std::string(code_name(o.code()))},
                       {"bit_size", o.bit_size()},
                       {"entries", std::move(entries)}});
  });
  nlohmann::json enums = nlohmann::json::array();
  for (const auto& [index, en] : od.enums()) {
    nlohmann::json values = nlohmann::json::array();
    for (const auto& v : en.values) values.push_back({{"value", v.value}, {"name", v.name}});
    enums.push_back({{"index", fmt::format("0x{:04X}", index)},
                     {"name", en.name},
                     {"bit_size", en.bit_size},
                     {"values", std::move(values)}});
  }
  std::cout << nlohmann::json{{"enums", enums}, {"objects", objects}}.dump(2) << "\n";
}

void print_layout_text(const mdp::Device& device, const PdoLayout& layout) {
  const unsigned out_bytes = device.output_bytes();
  std::printf(
      "process image of %s (current PDO assignment)\n"
      "offsets: byte.bit within the slave's output (SM2) or input (SM3) area; 'iomap' is the\n"
      "byte in a master's image holding this one slave (SOEM/pysoem: outputs first, then\n"
      "inputs): outputs at 0, inputs at %u\n",
      device.config().source.c_str(), out_bytes);
  for (int pass = 0; pass < 2; ++pass) {
    const bool output = pass == 0;
    std::printf(
        "\n%s: %u byte(s)\n",
        output ? "outputs (RxPDO, master -> slave, SM2)" : "inputs (TxPDO, slave -> master, SM3)",
        output ? device.output_bytes() : device.input_bytes());
    std::printf("  %6s %5s %3s %4s  %-6s  %-9s  %s\n", "iomap", "byte", "bit", "bits", "pdo",
                "entry", "name");
    for (const auto& e : layout.entries) {
      if (e.output != output) continue;
      const unsigned byte = e.bit_offset / 8;
      std::printf("  %6u %5u %3u %4u  0x%04X  %04X:%02X    %s\n", byte + (output ? 0 : out_bytes),
                  byte, e.bit_offset % 8, e.bits, e.pdo, e.index, e.subindex, e.name.c_str());
    }
  }
}

void print_layout_json(const mdp::Device& device, const PdoLayout& layout) {
  nlohmann::json entries = nlohmann::json::array();
  for (const auto& e : layout.entries) {
    const unsigned byte = e.bit_offset / 8;
    entries.push_back({{"direction", e.output ? "output" : "input"},
                       {"pdo", fmt::format("0x{:04X}", e.pdo)},
                       {"index", fmt::format("0x{:04X}", e.index)},
                       {"subindex", e.subindex},
                       {"bits", e.bits},
                       {"byte", byte},
                       {"bit", e.bit_offset % 8},
                       {"iomap_byte", byte + (e.output ? 0U : device.output_bytes())},
                       {"name", e.name}});
  }
  std::cout << nlohmann::json{{"output_bytes", device.output_bytes()},
                              {"input_bytes", device.input_bytes()},
                              {"entries", std::move(entries)}}
                   .dump(2)
            << "\n";
}

void run_od(const OdOptions& opt) {
  auto config = load_rack_or_report(opt.config);
  if (!config) exit_with(2);
  mdp::DeviceOptions dopt;
  dopt.state_dir = opt.state_dir;
  mdp::Device device(std::move(*config), dopt);
  if (opt.layout) {
    const PdoLayout layout = pdo_layout(device.dictionary());
    if (opt.format == "json") {
      print_layout_json(device, layout);
    } else {
      print_layout_text(device, layout);
    }
  } else if (opt.format == "json") {
    print_json(device.dictionary());
  } else {
    print_text(device.dictionary());
  }
  exit_with(0);
}

void add_od(CLI::App& app) {
  auto opt = std::make_shared<OdOptions>();
  auto* cmd = app.add_subcommand("od", "Print the object dictionary of the rack");
  cmd->add_option("--config", opt->config, "Rack file (YAML); default: the built-in rack");
  cmd->add_option("--format", opt->format, "Output format")->check(CLI::IsMember({"text", "json"}));
  cmd->add_option("--state-dir", opt->state_dir,
                  "Directory of the stored parameters (default $XDG_STATE_HOME/rackcat)");
  cmd->add_flag("--layout", opt->layout,
                "Print the process image instead: each PDO entry's byte and bit offset");
  cmd->callback([opt] { run_od(*opt); });
}

const CommandRegistrar reg{"od", add_od};

}  // namespace
}  // namespace rackcat::apps
