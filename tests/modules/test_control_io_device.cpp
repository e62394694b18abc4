// The control API on a line: a rack and a device from its ESI (modules/control/io_device.hpp)
// side by side, each addressed by its line position; the device's outputs read back, its
// inputs set, everything else refused with a reason and no change.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "modules/control/control_api.hpp"
#include "rack_fixture.hpp"

using namespace rackcat;
using namespace rackcat::modules;
using namespace rackcat::modules::testing;
using json = nlohmann::json;

namespace {

class FakeIo final : public IoDevice {
 public:
  std::string describe() const override { return "RC1008 'test DI'"; }
  std::vector<uint8_t> outputs() const override { return out; }
  std::vector<uint8_t> inputs() const override { return in; }
  void set_input_bits(size_t bit, size_t bits, std::span<const uint8_t> data) override {
    for (size_t i = 0; i < bits; ++i) {
      const bool v = (data[i / 8] >> (i % 8)) & 1;
      const size_t d = bit + i;
      in[d / 8] =
          static_cast<uint8_t>(v ? in[d / 8] | (1u << (d % 8)) : in[d / 8] & ~(1u << (d % 8)));
    }
  }
  std::vector<uint8_t> out{0x5A};
  std::vector<uint8_t> in{0x00, 0x00};
};

class ControlIoDeviceTest : public RackTest {
 protected:
  FakeIo io;
  ControlApi api{std::vector<ControlSlave>{{nullptr, &io}, {&rack, nullptr}}, nullptr,
                 ControlApiOptions{}};
  ControlApi::Response call(std::string_view method, std::string_view path, json body = nullptr) {
    return api.handle(method, path, body.is_null() ? std::string() : body.dump());
  }
};

}  // namespace

TEST_F(ControlIoDeviceTest, ListsBothKindsByLinePosition) {
  auto r = call("GET", "/api/slaves");
  ASSERT_EQ(r.status, 200);
  ASSERT_EQ(r.body["slaves"].size(), 2u);
  EXPECT_EQ(r.body["slaves"][0]["device"], "RC1008 'test DI'");
  EXPECT_TRUE(r.body["slaves"][1].contains("modules"));
  EXPECT_EQ(call("GET", "/api/slaves/1/rack").status, 200);
}

TEST_F(ControlIoDeviceTest, OutputsReadBackInputsSet) {
  auto r = call("GET", "/api/io");
  ASSERT_EQ(r.status, 200) << r.body.dump();
  EXPECT_EQ(r.body["outputs"], "5A");
  EXPECT_EQ(r.body["input_bits"], 16);
  r = call("POST", "/api/slaves/0/io/inputs", {{"data", "0F"}, {"bit", 6}, {"bits", 4}});
  ASSERT_EQ(r.status, 200) << r.body.dump();
  EXPECT_EQ(r.body["inputs"], "C003");
}

TEST_F(ControlIoDeviceTest, RefusalsChangeNothing) {
  auto r = call("POST", "/api/io/inputs", {{"data", "FFFF"}, {"bit", 4}});
  EXPECT_EQ(r.status, 400);
  EXPECT_EQ(r.body["error"],
            "input bits 4..19 are beyond the 16 input bit(s) of slave 0 (RC1008 'test DI')");
  EXPECT_EQ(call("POST", "/api/io/inputs", {{"data", "F"}}).status, 400);
  EXPECT_EQ(call("POST", "/api/io/inputs", {{"data", "FF"}, {"bits", 9}}).status, 400);
  EXPECT_EQ(call("POST", "/api/io/inputs", {{"data", "FF"}, {"bit", -1}}).status, 400);
  EXPECT_EQ(call("POST", "/api/io/inputs", {{"value", 1}}).status, 400);
  EXPECT_EQ(call("GET", "/api/io/inputs").status, 405);
  EXPECT_EQ(call("POST", "/api/io").status, 405);
  r = call("GET", "/api/esm");
  EXPECT_EQ(r.status, 404);
  EXPECT_EQ(r.body["error"],
            "slave 0 is RC1008 'test DI' from its ESI: it has GET /api/io and POST "
            "/api/io/inputs, not /api/esm");
  EXPECT_EQ(call("GET", "/api/slaves/2/io").status, 404);
  EXPECT_EQ(io.in, (std::vector<uint8_t>{0, 0}));
}
