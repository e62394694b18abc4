// The line file: the user's own EtherCAT line as rackcat runs it (docs/LINE.md). A YAML file
//
//   devices:                       # in wiring order, position 0 next to the master
//     - esi: devices.xml           # a device from its vendor ESI (device/esi_device.hpp) ...
//       device: RC1008             #   by Type/Name, or product_code: / revision:
//       name: di                   #   optional, for wiring
//       alias: 0x10                #   optional station alias (SII word 4, ETG.2010 Table 2)
//       count: 2                   #   optional, consecutive copies (serial 0..count-1)
//       modules: [RM-DI4, 0x2]     #   ETG.5001 modular device: the modules of its slots
//       inputs:                    #   optional, input fields driven by signal sources
//         - {bit: 0, bits: 16, source: sine, amplitude: 1000, period_s: 2}
//     - rack: rack.yaml            # ... or a Fusion.IO rack file
//   wiring:                        # outputs of one device looped back to inputs of another
//     - {from: do, from_bit: 0, to: di, to_bit: 0, bits: 8}
//
// Files named by the line file are read below the line file's own directory (mdp::FileRoot:
// no "..", no absolute path, no link out). Any problem is one FileError "FILE:LINE: reason",
// including a wiring cycle (a device whose inputs depend, through the wiring, on its own
// outputs) and a wire beyond a device's process data.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "device/esi_device.hpp"
#include "device/generic_device.hpp"
#include "mdp/rack_config.hpp"
#include "modules/signals/signal_source.hpp"

namespace rackcat::apps {

// An input field of an ESI device driven by one of the rack's signal sources (modules/signals:
// constant, ramp, sine, noise, clock, replay; docs/LINE.md "Signal sources"): every cycle bits
// [bit, bit + bits) of its inputs (SM3 layout, LSB first) carry the source's value then.
struct LineInput {
  size_t bit = 0, bits = 0;
  bool is_signed = true;  // a field of 2..64 bits: two's complement (else unsigned)
  double scale = 1.0;     // code = round(value x scale), clamped to the field
  std::shared_ptr<modules::Source> source;
  size_t line = 0;
  // The field's code for the source's value `value`: one bit is 1 from 0.5 on.
  uint64_t code(double value) const;
};

struct LineDevice {
  std::string name;  // from the file, or "" ; copies get "<name>#<k>" for k > 0
  size_t line = 0;   // line of the entry in the line file
  // Exactly one of:
  std::unique_ptr<device::EsiDevice> esi;
  std::unique_ptr<mdp::RackConfig> rack;
  std::vector<LineInput> inputs;  // esi: devices only
};

struct LineWire {
  size_t from = 0, to = 0;  // positions in LineFile::devices
  size_t from_bit = 0, to_bit = 0, bits = 0;
  size_t line = 0;
};

struct LineFile {
  std::string file;
  std::vector<LineDevice> devices;  // expanded (count applied), in line order
  std::vector<LineWire> wiring;
};

// Throws device::FileError.
LineFile load_line_file(const std::string& path);
LineFile parse_line_file(const std::string& yaml_text, const std::string& path);

}  // namespace rackcat::apps
