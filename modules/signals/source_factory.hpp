// Builds a channel's signal source from its description: the rack file's channel entry
// (kind + scalar parameters, mdp::ChannelOptions) or a control-API request. Parameter names
// (docs/MODULES.md "Signal sources"):
//   constant: value
//   ramp:     from, to, period_s
//   sine:     amplitude, offset, period_s | frequency (Hz), phase (rad)
//   noise:    mean, stddev, seed
//   replay:   file, loop (true/false)
//   loopback: the output channel (rack file: from {rim, slot, channel}; API: rim, slot,
//             channel or module, channel), gain, offset
//   plant:    plant (name), output (index); the first channel naming a plant defines it with
//             a, b, c[, d] ("1 0; 0 -2": rows separated by ';'), inputs ("rim.slot.channel"
//             output channels, comma separated, one per column of B), x0
// Unknown kinds, unknown or malformed parameters throw std::invalid_argument naming the
// parameter; nothing is changed then.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <string_view>

#include "modules/signals/signal_source.hpp"

namespace rackcat::modules {

class StateSpacePlant;

using SourceParams = std::map<std::string, std::string>;

struct OutputRef {
  const double* value = nullptr;  // the output channel's wire level
  std::string name;               // "rim1.slot11.out0"
};

struct SourceContext {
  // The live value of output `channel` of the card in RIM rim / slot; value = nullptr when
  // there is none (the error names the reason in `name`).
  std::function<OutputRef(uint8_t rim, uint8_t slot, uint8_t channel)> output;
  // Module number -> (rim, slot); false when unknown.
  std::function<bool(uint16_t module, uint8_t& rim, uint8_t& slot)> module_position;
  // Find or create the plant `name` (creating needs a/b/c in params).
  std::function<StateSpacePlant&(const std::string& name, const SourceParams& params)> plant;
  // Reads a replay file named by the description: below the directory the user named
  // (mdp::FileRoot: the rack file's directory, `--data-dir` for the control API). Unset: the
  // name is opened as given (unit tests only).
  std::function<std::string(const std::string& file, size_t max_bytes)> read_file;
};

// Keys every source accepts besides its own (handled by the rack: sensor options).
bool is_channel_option_key(std::string_view key);

std::unique_ptr<Source> make_source(std::string_view kind, const SourceParams& params,
                                    SourceContext& ctx);

// Plant construction from parameters (used by SourceContext::plant implementations).
std::unique_ptr<StateSpacePlant> make_plant(
    const SourceParams& params, double dt,
    const std::function<OutputRef(const std::string&)>& input);

// "1 0; 0 -2" -> matrix; throws std::invalid_argument.
struct MatrixText {
  size_t rows = 0, cols = 0;
  std::vector<double> values;  // row-major
};
MatrixText parse_matrix(std::string_view text, std::string_view what);

}  // namespace rackcat::modules
