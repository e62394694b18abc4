// Rack file parsing (yaml-cpp) and validation. Every problem becomes one ConfigError line
// "FILE:LINE: problem" with the line of the offending node (yaml-cpp marks are 0-based).
#include "mdp/rack_config.hpp"

#include <fmt/format.h>
#include <openssl/evp.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <charconv>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

namespace rackcat::mdp {

namespace {
// An error line stays one short line whatever the file holds: a problem that quotes a huge
// value is cut, and control characters (a value's own line breaks) become '?'.
std::string bounded(std::string text) {
  constexpr size_t kMax = 200;
  if (text.size() > kMax) {
    text = text.substr(0, kMax) + "... (" + std::to_string(text.size()) + " bytes)";
  }
  for (char& c : text) {
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7F) c = '?';
  }
  return text;
}
}  // namespace

ConfigError::ConfigError(std::string file, int line, std::string problem)
    // Line 0: the file as a whole (it cannot be read): "FILE: problem".
    : std::runtime_error(line > 0
                             ? bounded(file) + ":" + std::to_string(line) + ": " + bounded(problem)
                             : bounded(file) + ": " + bounded(problem)),
      file_(std::move(file)),
      line_(line),
      problem_(bounded(std::move(problem))) {}

namespace {

struct RimTypeInfo {
  RimType type;
  std::string_view name;
  uint8_t slots;
};
constexpr std::array<RimTypeInfo, 4> kRimTypes{{
    {RimType::Integrated24, "24-slot (integrated)", 24},
    {RimType::Slot24, "24-slot", 24},
    {RimType::Slot12, "12-slot", 12},
    {RimType::Slot6, "6-slot", 6},
}};

class Parser {
 public:
  explicit Parser(std::string file) : file_(std::move(file)) {}

  [[noreturn]] void fail(const YAML::Node& node, const std::string& problem) const {
    throw ConfigError(file_, node.Mark().line >= 0 ? node.Mark().line + 1 : 0, problem);
  }
  [[noreturn]] void fail_line(int line, const std::string& problem) const {
    throw ConfigError(file_, line, problem);
  }
  int line(const YAML::Node& node) const { return node.Mark().line + 1; }

  void require_map(const YAML::Node& node, const std::string& what) const {
    if (!node.IsMap()) fail(node, what + " must be a mapping");
  }
  void check_keys(const YAML::Node& node, std::initializer_list<std::string_view> allowed,
                  const std::string& what) const {
    for (const auto& kv : node) {
      const std::string key = kv.first.as<std::string>();
      if (std::find(allowed.begin(), allowed.end(), key) == allowed.end()) {
        fail(kv.first, fmt::format("unknown key '{}' in {}", key, what));
      }
    }
  }

  std::string string(const YAML::Node& node, const std::string& key, size_t max_len) const {
    if (!node.IsScalar()) fail(node, key + " must be a scalar");
    std::string s = node.as<std::string>();
    if (s.size() > max_len) {
      fail(node, key + " '" + s + "' is longer than " + std::to_string(max_len) + " characters");
    }
    return s;
  }

  uint64_t unsigned_int(const YAML::Node& node, const std::string& key, uint64_t max) const {
    if (!node.IsScalar()) fail(node, key + " must be a number");
    const std::string s = node.as<std::string>();
    uint64_t v = 0;
    const char* b = s.data();
    const char* e = s.data() + s.size();
    int base = 10;
    if (s.size() > 2 && s[0] == '0' && (s[1] == 'x' || s[1] == 'X')) {
      b += 2;
      base = 16;
    }
    auto [p, ec] = std::from_chars(b, e, v, base);
    if (ec != std::errc() || p != e || b == e) fail(node, key + " '" + s + "' is not a number");
    if (v > max)
      fail(node, key + " " + s + " is out of range (maximum " + std::to_string(max) + ")");
    return v;
  }

  bool boolean(const YAML::Node& node, const std::string& key) const {
    if (!node.IsScalar()) fail(node, key + " must be true/false or 1/0");
    const std::string s = node.as<std::string>();
    if (s == "1" || s == "true" || s == "yes" || s == "on") return true;
    if (s == "0" || s == "false" || s == "no" || s == "off") return false;
    fail(node, key + " '" + s + "' is not a boolean (true/false, 1/0)");
  }

  void control_module(const YAML::Node& n, ControlModule& cm) const {
    require_map(n, "control_module");
    check_keys(n,
               {"part_number", "firmware_version", "serial_number", "ipv4", "mac", "config_md5",
                "config_date", "vendor_id", "product_code", "revision", "serial", "vendor_name",
                "device_name", "hardware_version", "software_version", "bootloader_version"},
               "control_module");
    cm.line = line(n);
    if (n["part_number"]) cm.part_number = string(n["part_number"], "part_number", 64);
    if (n["firmware_version"])
      cm.firmware_version = string(n["firmware_version"], "firmware_version", 4);
    if (n["serial_number"]) cm.serial_number = string(n["serial_number"], "serial_number", 24);
    if (n["ipv4"]) {
      cm.ipv4 = string(n["ipv4"], "ipv4", 16);
      if (!is_valid_ipv4(cm.ipv4)) fail(n["ipv4"], "malformed IPv4 address '" + cm.ipv4 + "'");
    }
    if (n["mac"]) {
      cm.mac = string(n["mac"], "mac", 24);
      if (!is_valid_mac(cm.mac)) fail(n["mac"], "malformed MAC address '" + cm.mac + "'");
    }
    if (n["config_md5"]) cm.config_md5 = string(n["config_md5"], "config_md5", 24);
    if (n["config_date"]) {
      cm.config_date = string(n["config_date"], "config_date", 16);
      if (!is_valid_date(cm.config_date)) {
        fail(n["config_date"], "malformed config_date '" + cm.config_date + "' (YYYY-MM-DD)");
      }
    }
    if (n["vendor_id"]) cm.vendor_id = unsigned_int(n["vendor_id"], "vendor_id", 0xFFFFFFFF);
    if (n["product_code"])
      cm.product_code = unsigned_int(n["product_code"], "product_code", 0xFFFFFFFF);
    if (n["revision"]) cm.revision = unsigned_int(n["revision"], "revision", 0xFFFFFFFF);
    if (n["serial"]) cm.serial = unsigned_int(n["serial"], "serial", 0xFFFFFFFF);
    if (n["vendor_name"]) cm.vendor_name = string(n["vendor_name"], "vendor_name", 16);
    if (n["device_name"]) cm.device_name = string(n["device_name"], "device_name", 64);
    if (n["hardware_version"])
      cm.hardware_version = string(n["hardware_version"], "hardware_version", 16);
    if (n["software_version"])
      cm.software_version = string(n["software_version"], "software_version", 16);
    if (n["bootloader_version"])
      cm.bootloader_version = string(n["bootloader_version"], "bootloader_version", 6);
  }

  LoopbackRef loopback_ref(const YAML::Node& n, bool with_channel) const {
    require_map(n, "loopback source");
    if (with_channel) {
      check_keys(n, {"rim", "slot", "channel"}, "loopback source");
    } else {
      check_keys(n, {"rim", "slot"}, "loopback");
    }
    LoopbackRef ref;
    if (!n["rim"] || !n["slot"]) fail(n, "loopback source needs rim and slot");
    ref.rim = static_cast<uint8_t>(unsigned_int(n["rim"], "rim", 255));
    ref.slot = static_cast<uint8_t>(unsigned_int(n["slot"], "slot", 255));
    if (with_channel) {
      if (!n["channel"]) fail(n, "loopback source needs a channel");
      ref.channel = static_cast<uint8_t>(unsigned_int(n["channel"], "channel", 255));
    }
    return ref;
  }

  ChannelOptions channel(const YAML::Node& n, const CardType& card) const {
    require_map(n, "channel entry");
    ChannelOptions ch;
    ch.line = line(n);
    if (!n["channel"]) fail(n, "channel entry without 'channel'");
    const uint64_t c = unsigned_int(n["channel"], "channel", 255);
    if (c >= card.channels) {
      fail(n["channel"], "channel " + std::to_string(c) + " beyond the " +
                             std::to_string(card.channels) + " channels of " +
                             std::string(card.name));
    }
    ch.channel = static_cast<uint8_t>(c);
    for (const auto& kv : n) {
      const std::string key = kv.first.as<std::string>();
      if (key == "channel") continue;
      if (key == "source") {
        ch.source = string(kv.second, "source", 32);
        static constexpr std::array<std::string_view, 8> kSources{
            "constant", "ramp", "sine", "noise", "replay", "loopback", "plant", "clock"};
        if (std::find(kSources.begin(), kSources.end(), ch.source) == kSources.end()) {
          fail(kv.second, "unknown source '" + ch.source +
                              "' (constant, ramp, sine, noise, replay, loopback, plant, clock)");
        }
      } else if (key == "from" && kv.second.IsMap()) {
        ch.loopback = loopback_ref(kv.second, true);
        ch.loopback->line_hint = line(kv.second);
      } else if (kv.second.IsScalar()) {
        ch.params[key] = kv.second.as<std::string>();
      } else {
        fail(kv.first, "channel option '" + key + "' must be a scalar");
      }
    }
    if (ch.source == "loopback" && !ch.loopback) {
      fail(n, "loopback source needs 'from: {rim, slot, channel}'");
    }
    if (ch.loopback && ch.source.empty()) ch.source = "loopback";
    if (ch.loopback && ch.source != "loopback") {
      fail(n, "'from' is only valid with source: loopback");
    }
    return ch;
  }

  SlotCard slot(const YAML::Node& n, const Rim& rim) const {
    require_map(n, "slot entry");
    SlotCard sc;
    sc.line = line(n);
    if (!n["slot"]) fail(n, "slot entry without 'slot'");
    const uint64_t s = unsigned_int(n["slot"], "slot", 255);
    const uint8_t count = rim_slot_count(rim.type);
    if (s < 1 || s > count) {
      fail(n["slot"], "slot " + std::to_string(s) + " beyond RIM " + std::to_string(rim.number) +
                          " type " + std::string(rim_type_name(rim.type)) + " (slots 1.." +
                          std::to_string(count) + ")");
    }
    sc.slot = static_cast<uint8_t>(s);
    if (!n["card"]) {
      // A misspelt 'card' is an unknown key, not a missing card.
      for (const auto& kv : n) {
        const std::string key = kv.first.as<std::string>();
        if (key != "slot" && key != "channels" && key != "loopback" && key != "oversampling") {
          fail(kv.first, "slot " + std::to_string(s) + ": unknown key '" + key +
                             "' (a slot entry needs 'card')");
        }
      }
      fail(n, "slot " + std::to_string(s) + " without 'card'");
    }
    const YAML::Node cn = n["card"];
    const std::string text = string(cn, "card", 32);
    const CardType* card = nullptr;
    if (text.size() > 2 && text[0] == '0' && (text[1] == 'x' || text[1] == 'X')) {
      card = find_card(static_cast<uint16_t>(unsigned_int(cn, "card", 0xFFFF)));
    } else {
      card = find_card(std::string_view(text));
    }
    if (!card) fail(cn, "unknown card '" + text + "' (see the card catalogue in docs/MDP.md)");
    if (n["oversampling"]) {
      const uint64_t os = unsigned_int(n["oversampling"], "oversampling", 255);
      if (os == 8) {
        const CardType* v = oversampled_variant(*card);
        if (!v) {
          fail(n["oversampling"],
               "card " + std::string(card->name) + " has no 8x oversampled variant");
        }
        card = v;
      } else if (os != 1) {
        fail(n["oversampling"], "oversampling must be 1 or 8");
      }
    }
    sc.card = card;
    std::optional<LoopbackRef> card_loopback;
    int card_loopback_line = 0;
    for (const auto& kv : n) {
      const std::string key = kv.first.as<std::string>();
      if (key == "slot" || key == "card" || key == "oversampling") continue;
      if (key == "channels") {
        if (!kv.second.IsSequence()) fail(kv.second, "channels must be a list");
        std::set<uint8_t> seen;
        for (const auto& c : kv.second) {
          ChannelOptions ch = channel(c, *card);
          if (!seen.insert(ch.channel).second) {
            fail(c, "duplicate channel " + std::to_string(ch.channel));
          }
          sc.channels.push_back(std::move(ch));
        }
      } else if (key == "loopback") {
        card_loopback = loopback_ref(kv.second, false);
        card_loopback_line = line(kv.second);
      } else if (kv.second.IsScalar()) {
        sc.options[key] = kv.second.as<std::string>();
      } else {
        fail(kv.first, "slot option '" + key + "' must be a scalar");
      }
    }
    // Card-level loopback: channel i of this card reads channel i of the source card; channels
    // with their own source keep it.
    if (card_loopback) {
      for (uint8_t c = 0; c < card->channels; ++c) {
        const bool has_own = std::any_of(sc.channels.begin(), sc.channels.end(),
                                         [&](const ChannelOptions& o) { return o.channel == c; });
        if (has_own) continue;
        ChannelOptions ch;
        ch.channel = c;
        ch.source = "loopback";
        ch.loopback = *card_loopback;
        ch.loopback->channel = c;
        ch.loopback->line_hint = card_loopback_line;
        ch.line = card_loopback_line;
        sc.channels.push_back(ch);
      }
    }
    std::sort(
        sc.channels.begin(), sc.channels.end(),
        [](const ChannelOptions& a, const ChannelOptions& b) { return a.channel < b.channel; });
    return sc;
  }

  Rim rim(const YAML::Node& n) const {
    require_map(n, "RIM entry");
    check_keys(n,
               {"rim", "type", "part_number", "firmware_version", "serial_number",
                "unit_information", "fans", "slots"},
               "RIM entry");
    Rim r;
    r.line = line(n);
    if (!n["rim"]) fail(n, "RIM entry without 'rim' number");
    const uint64_t num = unsigned_int(n["rim"], "rim", 255);
    if (num < 1 || num > kMaxRims) {
      fail(n["rim"], "RIM number " + std::to_string(num) + " outside 1..5");
    }
    r.number = static_cast<uint8_t>(num);
    if (!n["type"]) fail(n, "RIM " + std::to_string(num) + " without 'type'");
    const std::string t = string(n["type"], "type", 24);
    const auto type = parse_rim_type(t);
    if (!type) {
      fail(n["type"],
           "unknown RIM type '" + t + "' (24-slot (integrated), 24-slot, 12-slot, 6-slot)");
    }
    r.type = *type;
    const std::string rr = std::to_string(r.number);
    r.part_number = n["part_number"] ? string(n["part_number"], "part_number", 64)
                                     : "FI-RM" + std::string(t.substr(0, 2)) + "00-00";
    r.firmware_version =
        n["firmware_version"] ? string(n["firmware_version"], "firmware_version", 4) : "0e";
    r.serial_number = n["serial_number"] ? string(n["serial_number"], "serial_number", 24)
                                         : r.part_number + "-000" + rr;
    if (n["unit_information"]) {
      r.unit_information = string(n["unit_information"], "unit_information", 32);
    } else {
      r.unit_information = r.type == RimType::Integrated24
                               ? "FUSION HIGH SIDE"
                               : "FUSION RIM " + std::to_string(rim_slot_count(r.type));
    }
    r.power_supply_fan = r.type == RimType::Integrated24;
    r.slot_card_fan = true;
    if (const auto f = n["fans"]) {
      require_map(f, "fans");
      check_keys(f, {"power_supply", "slot_card"}, "fans");
      if (f["power_supply"]) r.power_supply_fan = boolean(f["power_supply"], "power_supply");
      if (f["slot_card"]) r.slot_card_fan = boolean(f["slot_card"], "slot_card");
    }
    if (const auto s = n["slots"]) {
      if (!s.IsSequence()) fail(s, "slots must be a list");
      for (const auto& e : s) {
        SlotCard sc = slot(e, r);
        for (const auto& prev : r.slots) {
          if (prev.slot == sc.slot) {
            fail(e, "duplicate slot " + std::to_string(sc.slot) + " in RIM " + rr +
                        " (first at line " + std::to_string(prev.line) + ")");
          }
        }
        r.slots.push_back(std::move(sc));
      }
      std::sort(r.slots.begin(), r.slots.end(),
                [](const SlotCard& a, const SlotCard& b) { return a.slot < b.slot; });
    }
    return r;
  }

  RackConfig rack(const YAML::Node& root) const {
    RackConfig cfg;
    cfg.source = file_;
    if (root.IsNull()) fail_line(1, "empty rack file");
    require_map(root, "the rack file");
    check_keys(root, {"control_module", "detect_modules_override", "rims"}, "the rack file");
    if (root["control_module"]) control_module(root["control_module"], cfg.control);
    if (root["detect_modules_override"]) {
      cfg.detect_modules_override =
          boolean(root["detect_modules_override"], "detect_modules_override");
    }
    const auto rims = root["rims"];
    if (!rims) fail_line(1, "no 'rims' list");
    if (!rims.IsSequence()) fail(rims, "rims must be a list");
    for (const auto& e : rims) {
      Rim r = rim(e);
      for (const auto& prev : cfg.rims) {
        if (prev.number == r.number) {
          fail(e["rim"], "duplicate RIM " + std::to_string(r.number) + " (first at line " +
                             std::to_string(prev.line) + ")");
        }
      }
      cfg.rims.push_back(std::move(r));
    }
    std::sort(cfg.rims.begin(), cfg.rims.end(),
              [](const Rim& a, const Rim& b) { return a.number < b.number; });
    number_modules(cfg);
    resolve_loopbacks(cfg);
    return cfg;
  }

  void number_modules(RackConfig& cfg) const {
    std::array<uint16_t, 5> next_channel{};  // per ChannelClass
    for (size_t ri = 0; ri < cfg.rims.size(); ++ri) {
      const Rim& r = cfg.rims[ri];
      for (size_t si = 0; si < r.slots.size(); ++si) {
        const SlotCard& sc = r.slots[si];
        if (cfg.modules.size() == kMaxModules) {
          fail_line(sc.line, "more than 255 modules (RIM " + std::to_string(r.number) + " slot " +
                                 std::to_string(sc.slot) + " would be module 256)");
        }
        Module m;
        m.number = static_cast<uint16_t>(cfg.modules.size() + 1);
        m.rim = r.number;
        m.slot = sc.slot;
        m.card = sc.card;
        m.rim_pos = static_cast<uint16_t>(ri);
        m.slot_pos = static_cast<uint16_t>(si);
        auto& next = next_channel[static_cast<size_t>(sc.card->channel_class)];
        m.channel_low = next;
        m.channel_high = static_cast<uint16_t>(next + sc.card->channels - 1);
        next = static_cast<uint16_t>(next + sc.card->channels);
        cfg.modules.push_back(m);
      }
    }
  }

  void resolve_loopbacks(RackConfig& cfg) const {
    for (auto& r : cfg.rims) {
      for (auto& sc : r.slots) {
        for (auto& ch : sc.channels) {
          if (!ch.loopback) continue;
          LoopbackRef& ref = *ch.loopback;
          const Module* src = cfg.module_at(ref.rim, ref.slot);
          const int at = ref.line_hint ? ref.line_hint : ch.line;
          if (!src) {
            fail_line(at, "loopback source RIM " + std::to_string(ref.rim) + " slot " +
                              std::to_string(ref.slot) + " holds no card");
          }
          if (!src->card->output) {
            fail_line(at, "loopback source RIM " + std::to_string(ref.rim) + " slot " +
                              std::to_string(ref.slot) + " (" + std::string(src->card->name) +
                              ") has no outputs");
          }
          if (!sc.card->input) {
            fail_line(at, "card " + std::string(sc.card->name) + " has no inputs to wire");
          }
          if (ref.channel >= src->card->channels) {
            fail_line(at, "loopback source channel " + std::to_string(ref.channel) +
                              " beyond the " + std::to_string(src->card->channels) +
                              " channels of " + std::string(src->card->name));
          }
          ref.module = src->number;
        }
      }
    }
  }

 private:
  std::string file_;
};

std::string md5_base64(std::string_view text) {
  unsigned char md[EVP_MAX_MD_SIZE];
  unsigned int len = 0;
  // Without MD5 from libcrypto (a FIPS-only configuration) 0x2000:06 reads empty rather than
  // a made-up fingerprint; `config_md5` in the file still sets it.
  const EVP_MD* md5 = EVP_md5();
  if (md5 == nullptr || EVP_Digest(text.data(), text.size(), md, &len, md5, nullptr) != 1)
    return {};
  unsigned char b64[64] = {};
  const int n = EVP_EncodeBlock(b64, md, static_cast<int>(len));
  return std::string(reinterpret_cast<char*>(b64), static_cast<size_t>(n));
}

bool digits(std::string_view s, size_t pos, size_t n, int& value) {
  if (pos + n > s.size()) return false;
  value = 0;
  for (size_t i = pos; i < pos + n; ++i) {
    if (s[i] < '0' || s[i] > '9') return false;
    value = value * 10 + (s[i] - '0');
  }
  return true;
}

}  // namespace

std::string_view rim_type_name(RimType t) {
  for (const auto& i : kRimTypes) {
    if (i.type == t) return i.name;
  }
  return {};
}

uint8_t rim_slot_count(RimType t) {
  for (const auto& i : kRimTypes) {
    if (i.type == t) return i.slots;
  }
  return 0;
}

std::optional<RimType> parse_rim_type(std::string_view text) {
  for (const auto& i : kRimTypes) {
    if (i.name == text) return i.type;
  }
  return std::nullopt;
}

const Rim* RackConfig::rim(uint8_t number) const {
  for (const auto& r : rims) {
    if (r.number == number) return &r;
  }
  return nullptr;
}

const Module* RackConfig::module_at(uint8_t rim_number, uint8_t slot) const {
  for (const auto& m : modules) {
    if (m.rim == rim_number && m.slot == slot) return &m;
  }
  return nullptr;
}

RackConfig parse_rack_config(std::string_view yaml_text, const std::string& file) {
  YAML::Node root;
  try {
    root = YAML::Load(std::string(yaml_text));
  } catch (const YAML::ParserException& e) {
    throw ConfigError(file, e.mark.line + 1, "YAML syntax error: " + e.msg);
  }
  Parser parser(file);
  RackConfig cfg;
  try {
    cfg = parser.rack(root);
  } catch (const YAML::Exception& e) {
    // Conversion errors yaml-cpp raises while we read nodes (e.g. a key that is not a scalar).
    throw ConfigError(file, e.mark.line + 1, e.msg);
  }
  if (cfg.control.config_md5.empty()) cfg.control.config_md5 = md5_base64(yaml_text);
  return cfg;
}

RackConfig load_rack_config(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    throw ConfigError(path, 0, "cannot read the rack file: it is a directory");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    const int err = errno;
    throw ConfigError(path, 0, std::string("cannot read the rack file: ") + std::strerror(err));
  }
  std::ostringstream ss;
  ss << in.rdbuf();
  return parse_rack_config(ss.str(), path);
}

RackConfig default_rack() {
  return parse_rack_config(default_rack_yaml(), "<default rack>");
}

bool is_valid_ipv4(std::string_view text) {
  int parts = 0;
  size_t i = 0;
  while (parts < 4) {
    size_t start = i;
    int v = 0;
    while (i < text.size() && text[i] >= '0' && text[i] <= '9' && i - start < 3) {
      v = v * 10 + (text[i] - '0');
      ++i;
    }
    const size_t len = i - start;
    if (len == 0 || v > 255 || (len > 1 && text[start] == '0')) return false;
    ++parts;
    if (parts < 4) {
      if (i >= text.size() || text[i] != '.') return false;
      ++i;
    }
  }
  return i == text.size();
}

bool is_valid_mac(std::string_view text) {
  if (text.size() != 17) return false;
  const char sep = text[2];
  if (sep != ':' && sep != '-') return false;
  for (size_t i = 0; i < 17; ++i) {
    if (i % 3 == 2) {
      if (text[i] != sep) return false;
    } else if (!std::isxdigit(static_cast<unsigned char>(text[i]))) {
      return false;
    }
  }
  return true;
}

bool is_valid_date(std::string_view s) {
  int y = 0, m = 0, d = 0;
  if (s.size() != 10 || s[4] != '-' || s[7] != '-') return false;
  if (!digits(s, 0, 4, y) || !digits(s, 5, 2, m) || !digits(s, 8, 2, d)) return false;
  if (m < 1 || m > 12 || d < 1) return false;
  static constexpr std::array<int, 12> kDays{31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
  const bool leap = (y % 4 == 0 && y % 100 != 0) || y % 400 == 0;
  const int max = kDays[static_cast<size_t>(m - 1)] + (m == 2 && leap ? 1 : 0);
  return d <= max;
}

bool is_valid_clock(std::string_view s) {
  int hh = 0, mm = 0, ss = 0;
  if (s.size() != 19 || s[10] != ' ' || s[13] != ':' || s[16] != ':') return false;
  if (!is_valid_date(s.substr(0, 10))) return false;
  if (!digits(s, 11, 2, hh) || !digits(s, 14, 2, mm) || !digits(s, 17, 2, ss)) return false;
  return hh <= 23 && mm <= 59 && ss <= 59;
}

}  // namespace rackcat::mdp
