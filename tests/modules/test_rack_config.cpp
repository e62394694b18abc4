// Channel sources and card options from the rack file: a bad description fails with the
// rack file's name and line, a replay file is found next to the rack file.
#include <gtest/gtest.h>

#include <fstream>

#include "mdp/device.hpp"
#include "mdp/rack_config.hpp"
#include "modules/rack/rack.hpp"
#include "rack_fixture.hpp"

using namespace rackcat;
using namespace rackcat::modules;

namespace {
const char* kRack = R"(control_module: {part_number: FI-CM0100-00}
rims:
  - rim: 1
    type: 6-slot
    slots:
      - {slot: 1, card: CAO-15}
      - slot: 2
        card: CAI-11
        channels:
          - {channel: 0, source: replay, file: wave.csv, loop: false}
          - {channel: 1, source: sine, amplitude: 1, frequency: 2}
      - {slot: 3, card: CTP-11, cold_junction_c: 30}
)";

std::string write(const std::string& name, const std::string& text) {
  const std::string path = ::testing::TempDir() + name;
  std::ofstream(path) << text;
  return path;
}
}  // namespace

TEST(RackConfig, ReplayFileRelativeToTheRackFileAndCardOptions) {
  write("wave.csv", "0,1\n1,3\n");
  const std::string path = write("rack_ok.yaml", kRack);
  mdp::Device device(mdp::load_rack_config(path), modules::testing::device_options());
  double clock = 0.0;
  Rack rack(device, modules::testing::rack_options(&clock));
  clock = 0.5;  // sources run on the time since the rack started
  rack.before_inputs(device);
  EXPECT_NEAR(rack.driver_at(1, 2)->inputs()[0].value, 2.0, 1e-9);
  EXPECT_NEAR(rack.driver_at(1, 2)->inputs()[1].value, 0.0, 1e-9);  // sin(2*pi*2*0.5)
}

TEST(RackConfig, BadSourceFailsWithFileAndLine) {
  std::string text = kRack;
  text.replace(text.find("amplitude: 1"), 12, "amplitude: loud");
  const std::string path = write("rack_bad.yaml", text);
  mdp::Device device(mdp::load_rack_config(path), modules::testing::device_options());
  double clock = 0;
  try {
    Rack rack(device, modules::testing::rack_options(&clock));
    FAIL() << "expected a configuration error";
  } catch (const mdp::ConfigError& e) {
    EXPECT_EQ(e.file(), path);
    EXPECT_EQ(e.line(), 11);
    EXPECT_NE(e.problem().find("'amplitude'"), std::string::npos) << e.what();
  }
}

TEST(RackConfig, UnknownCardOptionFails) {
  std::string text = kRack;
  text.replace(text.find("cold_junction_c: 30"), 19, "colour: 30");
  const std::string path = write("rack_bad_option.yaml", text);
  mdp::Device device(mdp::load_rack_config(path), modules::testing::device_options());
  double clock = 0;
  EXPECT_THROW(Rack(device, modules::testing::rack_options(&clock)), mdp::ConfigError);
}
