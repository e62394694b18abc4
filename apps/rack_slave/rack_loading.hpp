// Loading the rack for a subcommand: the rack file given with --config, or the built-in
// default rack. Every subcommand that reads a rack file goes through load_rack_or_report, so
// `od`, `esi`, `sii`, `check`, `rim` and `run` accept and refuse the same files: the file is
// parsed (mdp::load_rack_config) and then the device and its slot-card drivers are built
// offline (mdp::Device + modules::Rack), which checks what only the drivers understand (card
// options, channel sources and their parameters, replay files, loopback targets). A bad file
// is one line "FILE:LINE: problem" on stderr and exit code 2.
#pragma once

#include <memory>
#include <optional>
#include <string>

#include "mdp/device.hpp"
#include "mdp/rack_config.hpp"

namespace rackcat::apps {

// The validated rack of `path` (empty: the built-in default rack), or nullopt after printing
// the configuration error.
std::optional<mdp::RackConfig> load_rack_or_report(const std::string& path);

// Throws mdp::ConfigError when the drivers refuse the rack (see above).
void validate_rack(const mdp::RackConfig& config);

// A device that describes the rack file as written (stored parameters not applied), for the
// files generated offline: ESI and SII.
std::unique_ptr<mdp::Device> offline_device(mdp::RackConfig config);

}  // namespace rackcat::apps
