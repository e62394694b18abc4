// libFuzzer target of the rack configuration parser: any text must either parse into a rack
// or be refused with mdp::ConfigError ("FILE:LINE: problem", docs/MDP.md). Any other
// exception, a crash, a hang or a sanitizer report is a bug. A text that parses is also
// built into a full mdp::Device (object dictionary, PDO mapping, SII-relevant sizes), since
// a configuration the parser accepts must never break the device built from it.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <string_view>

#include "mdp/device.hpp"
#include "mdp/rack_config.hpp"

namespace {

// The parameter store is never written here (nothing sends 0xFBF2 "save"), but the device
// still wants a state directory: a private one under the temp directory.
const std::string& state_dir() {
  static const std::string dir =
      (std::filesystem::temp_directory_path() / "rackcat-fuzz-mdp-config").string();
  return dir;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  rackcat::mdp::RackConfig config;
  try {
    config = rackcat::mdp::parse_rack_config(text, "fuzz.yaml");
  } catch (const rackcat::mdp::ConfigError& e) {
    // The documented outcome; the message must name the file.
    if (e.file() != "fuzz.yaml" || e.line() < 0) std::abort();
    return 0;
  }
  rackcat::mdp::DeviceOptions options;
  options.state_dir = state_dir();
  options.load_stored_parameters = false;
  rackcat::mdp::Device device(std::move(config), options);
  (void)device.output_bytes();
  (void)device.input_bytes();
  return 0;
}
