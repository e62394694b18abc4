// The rack file's channel sources for a RIM running as its own process (`rackcat rim`): the
// same source descriptions as in the emulated rack (modules/signals/source_factory.hpp), built for
// the RimNode's input channels. Loopbacks to output channels of the same RIM read that RIM's
// outputs as received in its RPDOs. A loopback to another RIM and plant sources need the
// whole rack (the control module's process): they are configuration errors here.
#pragma once

#include "mdp/rack_config.hpp"
#include "modules/rim/node.hpp"

namespace rackcat::modules::canopen {

// Throws mdp::ConfigError (file:line of the channel entry) for a source that cannot run.
void apply_rack_sources(RimNode& node, const mdp::RackConfig& rack);

}  // namespace rackcat::modules::canopen
