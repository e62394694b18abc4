// Line file reader (see line_file.hpp).
#include "apps/line/line_file.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <functional>
#include <map>
#include <set>

#include "device/esi_error.hpp"
#include "mdp/file_root.hpp"
#include "modules/signals/source_factory.hpp"

namespace rackcat::apps {
namespace {

constexpr size_t kMaxFileBytes = 64u << 20;

struct Parser {
  std::string file;
  std::shared_ptr<const mdp::FileRoot> root;

  [[noreturn]] void fail(const YAML::Node& at, const std::string& reason) const {
    throw device::FileError(file, at.IsDefined() ? static_cast<size_t>(at.Mark().line) + 1 : 0,
                            reason);
  }

  int64_t integer(const YAML::Node& n, const char* what) const {
    if (!n.IsScalar()) fail(n, std::string(what) + ": expected a number");
    const std::string& s = n.Scalar();
    try {
      size_t used = 0;
      const long long v = std::stoll(s, &used, 0);
      if (used != s.size()) throw std::invalid_argument(s);
      return v;
    } catch (const std::exception&) {
      fail(n, std::string(what) + ": \"" + s + "\" is not a number");
    }
  }

  std::string read(const YAML::Node& at, const std::string& relative) const {
    try {
      return root->read(relative, kMaxFileBytes);
    } catch (const std::exception& e) {
      fail(at, e.what());
    }
  }

  LineFile parse(const std::string& text) {
    YAML::Node doc;
    try {
      doc = YAML::Load(text);
    } catch (const YAML::Exception& e) {
      throw device::FileError(file, static_cast<size_t>(e.mark.line) + 1, e.msg);
    }
    LineFile out;
    out.file = file;
    if (!doc.IsMap()) throw device::FileError(file, 1, "a line file is a map with devices:");
    for (auto kv : doc) {
      const auto key = kv.first.Scalar();
      if (key != "devices" && key != "wiring") fail(kv.first, "unknown key \"" + key + "\"");
    }
    const auto devices = doc["devices"];
    if (!devices || !devices.IsSequence() || devices.size() == 0)
      throw device::FileError(file, 1, "devices: must list at least one device");
    std::map<std::string, size_t> by_name;
    for (const auto& d : devices) {
      if (!d.IsMap()) fail(d, "a device is a map with esi: or rack:");
      for (auto kv : d) {
        static const std::set<std::string> known = {"esi",     "device", "product_code", "revision",
                                                    "rack",    "name",   "alias",        "count",
                                                    "modules", "inputs"};
        if (!known.count(kv.first.Scalar()))
          fail(kv.first, "unknown device key \"" + kv.first.Scalar() + "\"");
      }
      const bool is_esi = static_cast<bool>(d["esi"]);
      const bool is_rack = static_cast<bool>(d["rack"]);
      if (is_esi == is_rack) fail(d, "a device has exactly one of esi: and rack:");
      const int64_t count = d["count"] ? integer(d["count"], "count") : 1;
      if (count < 1 || count > 256) fail(d["count"], "count must be 1..256");
      std::string name = d["name"] ? d["name"].Scalar() : "";
      if (!name.empty() && by_name.count(name)) fail(d["name"], "name \"" + name + "\" repeated");
      std::optional<uint16_t> alias;
      if (d["alias"]) {
        const auto a = integer(d["alias"], "alias");
        if (a < 0 || a > 0xFFFF) fail(d["alias"], "alias must be 0..0xFFFF");
        if (count > 1) fail(d["alias"], "alias with count > 1 would repeat the alias");
        alias = static_cast<uint16_t>(a);
      }
      std::unique_ptr<device::EsiDevice> esi_proto;
      std::unique_ptr<mdp::RackConfig> rack_proto;
      if (is_esi) {
        device::DeviceSelector sel;
        if (d["device"]) sel.name = d["device"].Scalar();
        if (d["product_code"])
          sel.product_code = static_cast<uint32_t>(integer(d["product_code"], "product_code"));
        if (d["revision"]) sel.revision = static_cast<uint32_t>(integer(d["revision"], "revision"));
        // ETG.5001 modular device: the modules in its slots, in order, by ModuleIdent or Type
        // (device/esi_device.hpp ModuleChoice); each error names the list element's line.
        if (const auto mods = d["modules"]) {
          if (!mods.IsSequence()) fail(mods, "modules: is a list of module idents or types");
          sel.modules.emplace();
          for (const auto& m : mods) {
            if (!m.IsScalar() || m.Scalar().empty())
              fail(m, "a module is its ModuleIdent (0x0064E001) or its Type text");
            sel.modules->push_back({m.Scalar(), file, static_cast<size_t>(m.Mark().line) + 1});
          }
        }
        const std::string esi_file = d["esi"].Scalar();
        const std::string xml = read(d["esi"], esi_file);
        esi_proto = std::make_unique<device::EsiDevice>(device::parse_esi_device(
            xml, (std::filesystem::path(root->path()) / esi_file).string(), sel));
        if (alias) esi_proto->description.config.station_alias = *alias;
      } else {
        if (d["device"] || d["product_code"] || d["revision"] || d["modules"] || d["inputs"])
          fail(d, "device:/product_code:/revision:/modules:/inputs: belong to an esi: device");
        if (alias)
          fail(d["alias"], "alias: on a rack: device is not supported (set it in the rack)");
        const std::string rack_file = d["rack"].Scalar();
        const std::string yaml = read(d["rack"], rack_file);
        try {
          rack_proto = std::make_unique<mdp::RackConfig>(mdp::parse_rack_config(
              yaml, (std::filesystem::path(root->path()) / rack_file).string()));
        } catch (const std::exception& e) {
          // The rack file's own FILE:LINE message, as `rackcat check` gives it.
          throw device::FileError(file, static_cast<size_t>(d["rack"].Mark().line) + 1,
                                  std::string("rack file: ") + e.what());
        }
      }
      for (int64_t k = 0; k < count; ++k) {
        LineDevice ld;
        ld.line = static_cast<size_t>(d.Mark().line) + 1;
        ld.name = name.empty() ? "" : (k == 0 ? name : name + "#" + std::to_string(k));
        if (esi_proto) {
          ld.esi = std::make_unique<device::EsiDevice>(*esi_proto);
          ld.esi->description.serial = static_cast<uint32_t>(k);
          if (d["inputs"]) ld.inputs = parse_inputs(d["inputs"], *ld.esi);
        } else {
          ld.rack = std::make_unique<mdp::RackConfig>(*rack_proto);
        }
        if (!ld.name.empty()) by_name[ld.name] = out.devices.size();
        out.devices.push_back(std::move(ld));
      }
    }
    if (const auto wiring = doc["wiring"]) {
      if (!wiring.IsSequence()) fail(wiring, "wiring: is a list of wires");
      for (const auto& w : wiring) parse_wire(w, by_name, out);
      check_cycles(out, wiring);
    }
    return out;
  }

  // inputs: [{bit, bits, source, signed, scale, <the source's parameters>}] (modules/signals
  // source_factory.hpp); each copy of a device gets its own sources.
  std::vector<LineInput> parse_inputs(const YAML::Node& list, const device::EsiDevice& esi) const {
    if (!list.IsSequence()) fail(list, "inputs: is a list of {bit, bits, source, ...}");
    const size_t in_bits = 8u * device::GenericDevice(esi).process_data_sizes().inputs;
    std::vector<LineInput> out;
    for (const auto& n : list) {
      if (!n.IsMap()) fail(n, "an input is {bit:, bits:, source:, ...the source's parameters}");
      LineInput in;
      in.line = static_cast<size_t>(n.Mark().line) + 1;
      in.bit = n["bit"] ? static_cast<size_t>(integer(n["bit"], "bit")) : 0;
      if (!n["bits"]) fail(n, "input without bits:");
      const auto bits = integer(n["bits"], "bits");
      if (bits < 1 || bits > 64) fail(n["bits"], "bits must be 1..64");
      in.bits = static_cast<size_t>(bits);
      if (!n["source"]) fail(n, "input without source: (constant, ramp, sine, noise, clock, ...)");
      if (in.bit + in.bits > in_bits)
        fail(n, "input bits " + std::to_string(in.bit) + ".." +
                    std::to_string(in.bit + in.bits - 1) + " but the device has " +
                    std::to_string(in_bits) + " input bits");
      for (const auto& other : out)
        if (other.bit < in.bit + in.bits && in.bit < other.bit + other.bits)
          fail(n, "input bits already driven by the source on line " + std::to_string(other.line));
      modules::SourceParams params;
      for (auto kv : n) {
        const std::string key = kv.first.Scalar();
        if (key == "bit" || key == "bits" || key == "source") continue;
        if (!kv.second.IsScalar()) fail(kv.second, key + ": is a scalar");
        if (key == "signed") {
          in.is_signed = kv.second.as<bool>(true);
          continue;
        }
        if (key == "scale") {
          try {
            in.scale = std::stod(kv.second.Scalar());
          } catch (const std::exception&) {
            fail(kv.second, "scale: is a number");
          }
          continue;
        }
        params[key] = kv.second.Scalar();
      }
      modules::SourceContext ctx;
      ctx.output = [](uint8_t, uint8_t, uint8_t) {
        return modules::OutputRef{nullptr, "rack channels are not in a line file's inputs"};
      };
      ctx.module_position = [](uint16_t, uint8_t&, uint8_t&) { return false; };
      ctx.plant = [&](const std::string&,
                      const modules::SourceParams&) -> modules::StateSpacePlant& {
        fail(n, "source plant is not supported for an ESI device's inputs");
      };
      ctx.read_file = [this](const std::string& f, size_t max) { return root->read(f, max); };
      const std::string kind = n["source"].Scalar();
      if (kind == "loopback" || kind == "plant")
        fail(n["source"],
             "source " + kind + " is not supported for an ESI device's inputs (use wiring:)");
      try {
        in.source = modules::make_source(kind, params, ctx);
      } catch (const std::exception& e) {
        fail(n, std::string("source ") + kind + ": " + e.what());
      }
      out.push_back(std::move(in));
    }
    return out;
  }

  size_t device_ref(const YAML::Node& n, const std::map<std::string, size_t>& by_name,
                    const LineFile& out) const {
    if (!n) fail(n, "wire without from:/to:");
    if (auto it = by_name.find(n.Scalar()); it != by_name.end()) return it->second;
    const auto pos = integer(n, "device position");
    if (pos < 0 || static_cast<size_t>(pos) >= out.devices.size())
      fail(n, "no device named or at position \"" + n.Scalar() + "\"");
    return static_cast<size_t>(pos);
  }

  void parse_wire(const YAML::Node& w, const std::map<std::string, size_t>& by_name,
                  LineFile& out) const {
    if (!w.IsMap()) fail(w, "a wire is {from:, to:, bits:, from_bit:, to_bit:}");
    LineWire wire;
    wire.line = static_cast<size_t>(w.Mark().line) + 1;
    wire.from = device_ref(w["from"], by_name, out);
    wire.to = device_ref(w["to"], by_name, out);
    wire.from_bit = w["from_bit"] ? static_cast<size_t>(integer(w["from_bit"], "from_bit")) : 0;
    wire.to_bit = w["to_bit"] ? static_cast<size_t>(integer(w["to_bit"], "to_bit")) : 0;
    if (!w["bits"]) fail(w, "wire without bits:");
    const auto bits = integer(w["bits"], "bits");
    if (bits < 1 || bits > 8 * 1024) fail(w["bits"], "bits must be 1..8192");
    wire.bits = static_cast<size_t>(bits);
    const auto& from = out.devices[wire.from];
    const auto& to = out.devices[wire.to];
    if (!from.esi || !to.esi)
      fail(w, "wiring connects esi: devices only (racks wire their own loopbacks)");
    // Sizes with the default assignment, as GenericDevice serves them.
    const size_t out_bits = 8u * device::GenericDevice(*from.esi).process_data_sizes().outputs;
    const size_t in_bits = 8u * device::GenericDevice(*to.esi).process_data_sizes().inputs;
    if (wire.from_bit + wire.bits > out_bits)
      fail(w, "wire reads output bits " + std::to_string(wire.from_bit) + ".." +
                  std::to_string(wire.from_bit + wire.bits - 1) + " but the device has " +
                  std::to_string(out_bits) + " output bits");
    if (wire.to_bit + wire.bits > in_bits)
      fail(w, "wire writes input bits " + std::to_string(wire.to_bit) + ".." +
                  std::to_string(wire.to_bit + wire.bits - 1) + " but the device has " +
                  std::to_string(in_bits) + " input bits");
    for (const auto& in : to.inputs)
      if (in.bit < wire.to_bit + wire.bits && wire.to_bit < in.bit + in.bits)
        fail(w, "input bits already driven by the source on line " + std::to_string(in.line));
    for (const auto& other : out.wiring) {
      if (other.to == wire.to && other.to_bit < wire.to_bit + wire.bits &&
          wire.to_bit < other.to_bit + other.bits)
        fail(w, "input bits already driven by the wire on line " + std::to_string(other.line));
    }
    out.wiring.push_back(wire);
  }

  // A device's inputs must not depend, through wires, on its own outputs.
  void check_cycles(const LineFile& out, const YAML::Node& wiring) const {
    const size_t n = out.devices.size();
    std::vector<int> color(n, 0);
    std::function<const LineWire*(size_t)> dfs = [&](size_t v) -> const LineWire* {
      color[v] = 1;
      for (const auto& w : out.wiring) {
        if (w.from != v) continue;
        if (color[w.to] == 1) return &w;
        if (color[w.to] == 0)
          if (const auto* c = dfs(w.to)) return c;
      }
      color[v] = 2;
      return nullptr;
    };
    for (size_t v = 0; v < n; ++v) {
      if (color[v] != 0) continue;
      if (const auto* w = dfs(v))
        throw device::FileError(file, w->line,
                                "wiring cycle: device " + std::to_string(w->to) +
                                    "'s inputs depend on its own outputs");
    }
    (void)wiring;
  }
};

}  // namespace

// Runs on the cyclic path: no allocation.
uint64_t LineInput::code(double value) const {
  if (bits == 1) return value >= 0.5 ? 1 : 0;
  const double v = std::round(value * scale);
  if (is_signed) {
    const double hi = std::ldexp(1.0, static_cast<int>(bits) - 1) - 1;
    const double lo = -hi - 1;
    const auto c = static_cast<int64_t>(std::isnan(v) ? 0 : std::clamp(v, lo, hi));
    return static_cast<uint64_t>(c);
  }
  const double hi = std::ldexp(1.0, static_cast<int>(bits)) - 1;
  return static_cast<uint64_t>(std::isnan(v) ? 0 : std::clamp(v, 0.0, hi));
}

LineFile parse_line_file(const std::string& yaml_text, const std::string& path) {
  Parser p;
  p.file = path;
  const auto dir = std::filesystem::path(path).parent_path();
  try {
    p.root = mdp::FileRoot::open(dir.empty() ? "." : dir.string());
  } catch (const std::exception& e) {
    throw device::FileError(path, 0, e.what());
  }
  return p.parse(yaml_text);
}

LineFile load_line_file(const std::string& path) {
  const auto p = std::filesystem::path(path);
  const auto dir = p.parent_path().empty() ? std::filesystem::path(".") : p.parent_path();
  std::shared_ptr<const mdp::FileRoot> root;
  std::string text;
  try {
    root = mdp::FileRoot::open(dir.string());
    text = root->read(p.filename().string(), kMaxFileBytes);
  } catch (const std::exception& e) {
    throw device::FileError(path, 0, e.what());
  }
  return parse_line_file(text, path);
}

}  // namespace rackcat::apps
