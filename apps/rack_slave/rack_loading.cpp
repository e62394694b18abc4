#include "apps/rack_slave/rack_loading.hpp"

#include <cstdio>
#include <utility>

#include "modules/rack/rack.hpp"

namespace rackcat::apps {

void validate_rack(const mdp::RackConfig& config) {
  const auto device = offline_device(config);
  // The drivers parse the card options and channel sources; nothing runs, nothing opens a
  // socket or a pseudo-terminal.
  const modules::Rack rack(*device);
}

std::optional<mdp::RackConfig> load_rack_or_report(const std::string& path) {
  try {
    mdp::RackConfig config = path.empty() ? mdp::default_rack() : mdp::load_rack_config(path);
    validate_rack(config);
    return config;
  } catch (const mdp::ConfigError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return std::nullopt;
  }
}

std::unique_ptr<mdp::Device> offline_device(mdp::RackConfig config) {
  mdp::DeviceOptions options;
  options.load_stored_parameters = false;
  return std::make_unique<mdp::Device>(std::move(config), options);
}

}  // namespace rackcat::apps
