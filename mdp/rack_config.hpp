// The rack description: control module identity, RIMs 1..5 with their slot cards and per-channel
// options, loaded from a YAML file (yaml-cpp) or the built-in default rack. Modules are numbered
// RIM by RIM, slot by slot (ETG.5001.1 module position order; guide §1 "nn = module number - 1").
//
// Every configuration error is a ConfigError whose what() is ONE line "FILE:LINE: problem"
// ("FILE: problem" when it concerns the file as a whole, e.g. it cannot be read);
// the apps map it to exit code 2. The file format is documented in docs/MDP.md and
// examples/default-rack.yaml.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "mdp/card_catalogue.hpp"

namespace rackcat::mdp {

class ConfigError : public std::runtime_error {
 public:
  ConfigError(std::string file, int line, std::string problem);
  const std::string& file() const { return file_; }
  int line() const { return line_; }  // 1-based; 0 when no line applies
  const std::string& problem() const { return problem_; }

 private:
  std::string file_;
  int line_;
  std::string problem_;
};

// The guide's RIM types (0x2rr1:04) and their slot counts.
enum class RimType : uint8_t { Integrated24, Slot24, Slot12, Slot6 };
std::string_view rim_type_name(RimType t);  // "24-slot (integrated)", "24-slot", ...
uint8_t rim_slot_count(RimType t);
std::optional<RimType> parse_rim_type(std::string_view text);

// Control module (0x1018, 0x2000, 0xF9F0, 0xF9F3, SII identity).
struct ControlModule {
  std::string part_number = "FI-CM0100-00";         // 0x2000:01 "CC-CCCCCC-CC"
  std::string firmware_version = "6b";              // 0x2000:02 string(4)
  std::string serial_number = "FI-CM0100-00-0001";  // 0x2000:03 "<part number>-NNNN"
  std::string ipv4 = "192.168.9.50";                // 0x2000:04 default per guide Table 1
  std::string mac = "02:00:5e:00:53:01";            // 0x2000:05 (locally administered)
  std::string config_md5;                           // 0x2000:06 (empty: MD5 of the rack file)
  std::string config_date = "2026-01-01";           // 0x2000:07 "YYYY-MM-DD"
  // Not an ETG-assigned vendor ID: 0x00000000 is reserved/unassigned in the ETG vendor list;
  // users who publish their own ESI must set their own assigned ID (docs/MDP.md).
  uint32_t vendor_id = 0x00000000;                           // 0x1018:01
  uint32_t product_code = 0x00464E01;                        // 0x1018:02
  uint32_t revision = 0x00010009;                            // 0x1018:03
  uint32_t serial = 1;                                       // 0x1018:04
  std::string vendor_name = "rackcat";                       // 0xF9F3 string(16)
  std::string device_name = "rackcat Fusion.IO-style rack";  // 0x1008
  std::string hardware_version = "1.0";                      // 0x1009
  std::string software_version = "1.09.6";                   // 0x100A
  std::string bootloader_version = "1.09.0";                 // 0x100B string(6)
  uint16_t boot_mailbox_size = 512;  // bootstrap SM0/SM1 bytes (mdp/sync_manager_layout.hpp)
  // The password every FoE read and write request must carry (docs/FOE.md); the default is
  // "RCFW" read as a big-endian UINT32.
  uint32_t foe_password = 0x52434657;
  int line = 0;
};

// Where an input channel's value comes from (driven by modules/). `kind` is the source name
// from the file: "constant", "ramp", "sine", "noise", "replay", "loopback", "plant", "clock";
// `params` keeps every other scalar key of the channel entry verbatim for the source's own parser.
struct LoopbackRef {
  uint8_t rim = 0;
  uint8_t slot = 0;
  uint8_t channel = 0;
  uint16_t module = 0;  // resolved module number (1..255) of rim/slot, after numbering
  int line_hint = 0;    // rack-file line of the reference (for error messages)
};
struct ChannelOptions {
  uint8_t channel = 0;  // 0-based channel of the card
  std::string source;   // "" = card default
  std::map<std::string, std::string> params;
  std::optional<LoopbackRef> loopback;  // source "loopback": wired to this output channel
  int line = 0;
};

struct SlotCard {
  uint8_t slot = 0;  // 1..slot count of the RIM type
  const CardType* card = nullptr;
  std::vector<ChannelOptions> channels;        // only channels with options, in channel order
  std::map<std::string, std::string> options;  // other scalar keys of the slot entry
  int line = 0;
};

struct Rim {
  uint8_t number = 0;  // 1..5
  RimType type = RimType::Slot12;
  std::string part_number;        // 0x2rr1:01
  std::string firmware_version;   // 0x2rr1:02
  std::string serial_number;      // 0x2rr1:03
  std::string unit_information;   // 0x2rr1:05
  bool power_supply_fan = false;  // 0x2rr1:0A/0C read -100 / 0 without the fan
  bool slot_card_fan = true;      // 0x2rr1:0B/0D
  std::vector<SlotCard> slots;    // by slot number
  int line = 0;
};

// One EtherCAT module (ETG.5001): a slot card at its position in the numbering.
struct Module {
  uint16_t number = 0;  // 1..255
  uint8_t rim = 0;
  uint8_t slot = 0;
  const CardType* card = nullptr;
  uint16_t rim_pos = 0;       // position in RackConfig::rims
  uint16_t slot_pos = 0;      // position in Rim::slots
  uint16_t channel_low = 0;   // 0x3nn1:06
  uint16_t channel_high = 0;  // 0x3nn1:07

  uint16_t nn() const { return static_cast<uint16_t>(number - 1); }
  // 0xAnnX of this module: index(0x6000, 0x0) is its DINx16 object, index(0x3000, 1) 0x3nn1.
  uint16_t index(uint16_t area_base, uint8_t nibble) const {
    return module_index(area_base, number, nibble);
  }
};

struct RackConfig {
  std::string source;  // file path, or "<default rack>"
  ControlModule control;
  bool detect_modules_override = true;  // 0x2000:0B default (guide Table 23: 1 = default)
  std::vector<Rim> rims;                // ascending RIM number
  std::vector<Module> modules;          // numbered RIM by RIM, slot by slot

  const Rim* rim(uint8_t number) const;
  const Module* module_at(uint8_t rim, uint8_t slot) const;
  // The slot entry (card options, channel sources) a module was built from.
  const SlotCard& slot_card(const Module& m) const { return rims[m.rim_pos].slots[m.slot_pos]; }
};

// Parses YAML text; `file` names it in errors. Throws ConfigError.
RackConfig parse_rack_config(std::string_view yaml_text, const std::string& file);
// Reads and parses a file. Throws ConfigError (unreadable file: line 0).
RackConfig load_rack_config(const std::string& path);
// The built-in default rack (examples/default-rack.yaml holds the same text).
std::string_view default_rack_yaml();
RackConfig default_rack();

// Validators shared with the object dictionary (0x2000:04, 0x2000:05, 0x2000:07, 0x2000:08).
bool is_valid_ipv4(std::string_view text);   // dotted quad, 0..255, no leading zeros
bool is_valid_mac(std::string_view text);    // aa:bb:cc:dd:ee:ff (hex, ':' or '-')
bool is_valid_date(std::string_view text);   // YYYY-MM-DD, real calendar date
bool is_valid_clock(std::string_view text);  // YYYY-MM-DD HH:MM:SS

}  // namespace rackcat::mdp
