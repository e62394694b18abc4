// Loading the rack for a subcommand: the rack file given with --config, or the built-in
// default rack. Every subcommand reports a bad file the same way: one line
// "FILE:LINE: problem" on stderr and exit code 2.
#pragma once

#include <memory>
#include <optional>
#include <string>

#include "mdp/device.hpp"
#include "mdp/rack_config.hpp"

namespace rackcat::apps {

// The rack of `path` (empty: the built-in default rack), or nullopt after printing the
// configuration error.
std::optional<mdp::RackConfig> load_rack_or_report(const std::string& path);

// A device that describes the rack file as written (stored parameters not applied), for the
// files generated offline: ESI and SII.
std::unique_ptr<mdp::Device> offline_device(mdp::RackConfig config);

}  // namespace rackcat::apps
