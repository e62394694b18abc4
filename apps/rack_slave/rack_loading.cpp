#include "apps/rack_slave/rack_loading.hpp"

#include <cstdio>
#include <utility>

namespace rackcat::apps {

std::optional<mdp::RackConfig> load_rack_or_report(const std::string& path) {
  try {
    return path.empty() ? mdp::default_rack() : mdp::load_rack_config(path);
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
