// The fault-injection control API: requests as `rackcat ctl` sends them, answers in JSON,
// invalid requests refused with a reason and no change.
#include <httplib.h>

#include <nlohmann/json.hpp>

#include "modules/control/control_api.hpp"
#include "rack_fixture.hpp"

using namespace rackcat;
using namespace rackcat::modules;
using namespace rackcat::modules::testing;
using json = nlohmann::json;

namespace {
class ControlApiTest : public RackTest {
 protected:
  ControlApi api{rack, nullptr};
  ControlApi::Response call(std::string_view method, std::string_view path, json body = nullptr) {
    return api.handle(method, path, body.is_null() ? std::string() : body.dump());
  }
};
}  // namespace

TEST_F(ControlApiTest, ListsRimsModulesAndChannels) {
  auto r = call("GET", "/api/rack");
  ASSERT_EQ(r.status, 200);
  EXPECT_EQ(r.body["esm"], "INIT");
  EXPECT_EQ(r.body["rims"].size(), 2u);
  EXPECT_EQ(r.body["modules"].size(), device.modules().size());
  const json& cdi = r.body["modules"][1];
  EXPECT_EQ(cdi["card"], "CDI-10");
  EXPECT_EQ(cdi["inputs"].size(), 16u);
  EXPECT_NE(cdi["inputs"][0]["source"].get<std::string>().find("loopback"), std::string::npos);
  auto one = call("GET", "/api/modules/19");
  ASSERT_EQ(one.status, 200);
  EXPECT_EQ(one.body["uart"].size(), 4u);
  EXPECT_EQ(call("GET", "/api/modules/999").status, 404);
}

TEST_F(ControlApiTest, SetsAChannelValueOrSource) {
  const uint16_t n = at(1, 12).module().number;
  auto r = call("POST", "/api/channel", {{"module", n}, {"channel", 3}, {"value", 1.25}});
  ASSERT_EQ(r.status, 200) << r.body.dump();
  EXPECT_DOUBLE_EQ(r.body["inputs"][3]["value"].get<double>(), 1.25);
  r = call("POST", "/api/channel",
           {{"module", n},
            {"channel", 4},
            {"source", "sine"},
            {"params", {{"amplitude", 2}, {"frequency", 50}}}});
  ASSERT_EQ(r.status, 200) << r.body.dump();
  EXPECT_NE(r.body["inputs"][4]["source"].get<std::string>().find("sine"), std::string::npos);
}

TEST_F(ControlApiTest, InvalidRequestsGetAReasonAndChangeNothing) {
  const uint16_t n = at(1, 12).module().number;
  const std::string before = at(1, 12).inputs()[0].source->describe();
  struct Case {
    const char* method;
    const char* path;
    json body;
    const char* reason;
  };
  const Case cases[] = {
      {"POST",
       "/api/channel",
       {{"module", n}, {"channel", 0}, {"source", "square"}},
       "unknown source"},
      {"POST", "/api/channel", {{"module", n}, {"channel", 99}, {"value", 1}}, "'channel' must be"},
      {"POST",
       "/api/channel",
       {{"module", n}, {"channel", 8}, {"value", 1}},
       "has 8 input channels"},
      {"POST",
       "/api/channel",
       {{"module", "x"}, {"channel", 0}, {"value", 1}},
       "'module' must be an integer"},
      {"POST",
       "/api/channel",
       {{"module", n},
        {"channel", 0},
        {"source", "sine"},
        {"params", {{"amplitude", "big"}, {"period_s", 1}}}},
       "'amplitude'"},
      {"POST", "/api/rim/unplug", {{"rim", 4}}, "no RIM 4"},
      {"POST",
       "/api/fan",
       {{"rim", 2}, {"zone", "power_supply"}, {"rpm", 10}},
       "no power-supply fan"},
      {"POST", "/api/fan", {{"rim", 1}, {"zone", "slot_card"}, {"rpm", -5}}, "rpm must be"},
      {"POST",
       "/api/wiring_fault",
       {{"module", at(1, 5).module().number}, {"channel", 0}, {"fault", "safe"}},
       "cannot detect wiring faults"},
      {"POST",
       "/api/sensor",
       {{"module", n}, {"channel", 0}, {"open", true}},
       "not a thermocouple"},
      {"POST", "/api/uart/inject", {{"module", n}, {"channel", 0}, {"text", "x"}}, "not a UART"},
      {"POST", "/api/uart/inject", {{"module", 19}, {"channel", 0}, {"hex", "abc"}}, "odd number"},
      {"POST", "/api/cpu_temperature", {{"celsius", 1000}}, "must be -55..150"},
      {"GET", "/api/channel", nullptr, "does not accept GET"},
      {"GET", "/api/nothing", nullptr, "no endpoint"},
  };
  for (const Case& c : cases) {
    auto r = call(c.method, c.path, c.body);
    EXPECT_GE(r.status, 400) << c.path << " " << c.body.dump();
    ASSERT_TRUE(r.body.contains("error")) << r.body.dump();
    EXPECT_NE(r.body["error"].get<std::string>().find(c.reason), std::string::npos)
        << r.body["error"] << " for " << c.body.dump();
  }
  // Replay files must be regular, bounded files; a bad one is a bad request.
  for (const char* file : {"/nonexistent/wave.csv", "/dev/zero"}) {
    auto r =
        call("POST", "/api/channel",
             {{"module", n}, {"channel", 0}, {"source", "replay"}, {"params", {{"file", file}}}});
    EXPECT_EQ(r.status, 400) << file;
    EXPECT_NE(r.body["error"].get<std::string>().find("regular file"), std::string::npos);
  }
  // Request bytes echoed in an answer are made printable so the answer stays valid JSON.
  auto odd = api.handle("GET", "/api/\xff\xfe", "");
  EXPECT_EQ(odd.status, 404);
  EXPECT_NO_THROW((void)odd.body.dump());
  auto bad_json = api.handle("POST", "/api/channel", "{not json");
  EXPECT_EQ(bad_json.status, 400);
  EXPECT_EQ(at(1, 12).inputs()[0].source->describe(), before);
  EXPECT_EQ(obj(0x2021).get_u(8), 2u);
}

TEST_F(ControlApiTest, FaultInjectionEndpoints) {
  auto r = call("POST", "/api/rim/unplug", {{"rim", 2}});
  ASSERT_EQ(r.status, 200);
  EXPECT_EQ(r.body["F388"], "0x00000004");
  EXPECT_EQ(r.body["rims"][1]["event_status"], "0x00000008");
  r = call("POST", "/api/rim/replug", {{"rim", 2}});
  EXPECT_EQ(r.body["F380"], "0x00000000");
  EXPECT_EQ(r.body["F390"], "0x00000008");
  r = call("POST", "/api/fan", {{"rim", 0}, {"zone", "cpu"}, {"rpm", 1000}});
  EXPECT_EQ(r.body["device_event_status"], "0x00000700");
  r = call("POST", "/api/cpu_temperature", {{"celsius", 55.2}, {"immediate", true}});
  EXPECT_DOUBLE_EQ(r.body["published"].get<double>(), 55.0);
  const uint16_t tc = at(1, 16).module().number;
  r = call("POST", "/api/sensor", {{"module", tc}, {"channel", 2}, {"open", true}});
  EXPECT_EQ(r.body["inputs"][2]["code"], 0x7FFF);
  r = call("POST", "/api/uart/inject",
           {{"module", 19}, {"channel", 1}, {"text", "AT"}, {"hex", "0d0a"}});
  ASSERT_EQ(r.status, 200) << r.body.dump();
  EXPECT_EQ(r.body["uart"][1]["rx_available"], 4);
  const uint16_t sout = at(1, 1).module().number;
  r = call("POST", "/api/wiring_fault", {{"module", sout}, {"channel", 0}, {"fault", "unsafe"}});
  EXPECT_EQ(r.body["rims"][0]["state"], "error");
  EXPECT_EQ(call("GET", "/api/esm").body["state"], "INIT");
  EXPECT_EQ(call("GET", "/api/exceptions").status, 200);
}

TEST_F(ControlApiTest, ServesHttpOnLocalhostThroughThePostFunction) {
  int posted = 0;
  ControlApi http(rack, [&](std::function<void()> f) {
    ++posted;
    f();  // the test thread stands in for the device thread
  });
  const uint16_t port = http.listen(0);
  ASSERT_GT(port, 0);
  httplib::Client cli("127.0.0.1", port);
  auto res = cli.Get("/api/esm");
  ASSERT_TRUE(res);
  EXPECT_EQ(res->status, 200);
  EXPECT_EQ(json::parse(res->body)["state"], "INIT");
  auto bad = cli.Post("/api/rim/unplug", R"({"rim": 9})", "application/json");
  ASSERT_TRUE(bad);
  EXPECT_EQ(bad->status, 400);
  EXPECT_NE(json::parse(bad->body)["error"].get<std::string>().find("'rim' must be 1..5"),
            std::string::npos);
  EXPECT_EQ(posted, 2);
  http.stop();
}
