// `rackcat od [--config FILE] [--format text|json] [--state-dir DIR]`: prints the whole object
// dictionary of the rack (index, subindex, name, type, bit size, access, PDO mapping, value),
// with stored parameters applied as the running device would load them.
#include <fmt/format.h>

#include <cstdio>
#include <cstring>
#include <iostream>
#include <nlohmann/json.hpp>
#include <string>

#include "apps/commands.hpp"
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
    if (o.hooks.before_read) o.hooks.before_read(o, -1);
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
    if (o.hooks.before_read) o.hooks.before_read(o, -1);
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

void run_od(const OdOptions& opt) {
  auto config = load_rack_or_report(opt.config);
  if (!config) exit_with(2);
  mdp::DeviceOptions dopt;
  dopt.state_dir = opt.state_dir;
  mdp::Device device(std::move(*config), dopt);
  if (opt.format == "json") {
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
  cmd->callback([opt] { run_od(*opt); });
}

const CommandRegistrar reg{"od", add_od};

}  // namespace
}  // namespace rackcat::apps
