// The fault-injection control API: requests as `rackcat ctl` sends them, answers in JSON,
// invalid requests refused with a reason and no change.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <thread>

#include <nlohmann/json.hpp>

#include "mdp/file_root.hpp"
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
  const std::string before = at(1, 12).source(0).describe();
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
      {"GET", "/api/channel", nullptr, "does not accept GET; use POST"},
      {"GET", "/api/nothing", nullptr, "no endpoint"},
      // A misspelt key is named, not reported as another field missing.
      {"POST", "/api/channel", {{"valu", 1}}, "unknown field 'valu' (/api/channel takes module"},
      {"POST", "/api/channel", {{"module", n}, {"channel", 0}}, "give 'value' or 'source'"},
      {"POST",
       "/api/fan",
       {{"rim", 1}, {"rpm", 10}, {"zone", "cpu"}, {"speed", 1}},
       "unknown field 'speed'"},
      {"POST", "/api/rim/replug", {{"rim", 2}, {"comm_error", true}}, "unknown field 'comm_error'"},
      {"POST", "/api/rim/mcm", {{"rim", 1}, {"errors", {"bogus"}}}, "entry \"bogus\" is not one"},
      {"POST", "/api/wiring_fault", json::array({1}), "must be a JSON object"},
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
    EXPECT_NE(r.body["error"].get<std::string>().find("--data-dir"), std::string::npos);
  }
  // Request bytes echoed in an answer are made printable so the answer stays valid JSON.
  auto odd = api.handle("GET", "/api/\xff\xfe", "");
  EXPECT_EQ(odd.status, 404);
  EXPECT_NO_THROW((void)odd.body.dump());
  auto bad_json = api.handle("POST", "/api/channel", "{not json");
  EXPECT_EQ(bad_json.status, 400);
  EXPECT_EQ(at(1, 12).source(0).describe(), before);
  EXPECT_EQ(obj(0x2021).get_u(8), 2u);
}

// RFC 9110 §15.5.6: a 405 names the method the endpoint accepts in Allow.
TEST_F(ControlApiTest, WrongMethodNamesTheAcceptedOne) {
  auto r = call("GET", "/api/wiring_fault");
  EXPECT_EQ(r.status, 405);
  EXPECT_EQ(r.allow, "POST");
  r = call("POST", "/api/esm", json::object());
  EXPECT_EQ(r.status, 405);
  EXPECT_EQ(r.allow, "GET");
  r = call("POST", "/api/slaves", json::object());
  EXPECT_EQ(r.status, 405);
  EXPECT_EQ(r.allow, "GET");
}

// Every answer to a change shows the state after it: the value just set, the wire of
// the faulted channel and the fan's new speed, with the exception tree they feed.
TEST_F(ControlApiTest, AnswersShowTheStateAfterTheChange) {
  const uint16_t ain = at(1, 12).module().number;
  auto r = call("POST", "/api/channel", {{"module", ain}, {"channel", 2}, {"value", -2.5}});
  ASSERT_EQ(r.status, 200) << r.body.dump();
  EXPECT_DOUBLE_EQ(r.body["inputs"][2]["value"].get<double>(), -2.5);
  const uint16_t sout = at(1, 1).module().number;
  r = call("POST", "/api/wiring_fault", {{"module", sout}, {"channel", 3}, {"fault", "unsafe"}});
  ASSERT_EQ(r.status, 200) << r.body.dump();
  EXPECT_EQ(r.body["module_state"]["outputs"][3]["wiring_fault"], "unsafe");
  EXPECT_DOUBLE_EQ(r.body["module_state"]["outputs"][3]["wire"].get<double>(), 1.0);
  ASSERT_FALSE(r.body["modules"].empty());
  EXPECT_EQ(r.body["modules"][0]["F384"], "0x00000008");  // channel 3's error bit (guide §3.4)
  r = call("POST", "/api/wiring_fault", {{"module", sout}, {"channel", 3}, {"fault", "none"}});
  EXPECT_EQ(r.body["module_state"]["outputs"][3]["wiring_fault"], "none");
  EXPECT_EQ(r.body["modules"][0]["F384"], "0x00000000");
  r = call("POST", "/api/fan", {{"rim", 1}, {"zone", "slot_card"}, {"rpm", 1200}});
  ASSERT_EQ(r.status, 200) << r.body.dump();
  EXPECT_DOUBLE_EQ(r.body["fans"]["rims"][0]["slot_card_rpm"].get<double>(), 1200.0);
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

namespace {

// One raw HTTP exchange on 127.0.0.1:port; returns the whole answer ("" when none).
std::string http_exchange(uint16_t port, const std::string& request) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(port);
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
    ::close(fd);
    return {};
  }
  timeval tv{5, 0};
  ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  (void)!::send(fd, request.data(), request.size(), MSG_NOSIGNAL);
  std::string out;
  char buf[4096];
  for (ssize_t n; (n = ::recv(fd, buf, sizeof buf, 0)) > 0;)
    out.append(buf, static_cast<size_t>(n));
  ::close(fd);
  return out;
}

int status_of(const std::string& answer) {
  return answer.size() > 12 ? std::atoi(answer.c_str() + 9) : 0;
}

const std::string kToken = "0123456789abcdef0123456789abcdef";

std::string http_request(uint16_t port, const std::string& method, const std::string& path,
                         const std::string& body, const std::string& extra,
                         const std::string& type = "application/json") {
  std::string r =
      method + " " + path + " HTTP/1.1\r\nHost: 127.0.0.1:" + std::to_string(port) + "\r\n" + extra;
  if (!body.empty()) {
    r += "Content-Type: " + type + "\r\nContent-Length: " + std::to_string(body.size()) + "\r\n";
  }
  return r + "\r\n" + body;
}

}  // namespace

// Issue 14 item 1: every request needs the token, the API's own Host, no foreign Origin and a
// JSON body; refused requests change nothing and never reach the device thread.
TEST_F(ControlApiTest, RefusesForeignHostOriginTokenlessAndNonJsonRequests) {
  int posted = 0;
  ControlApiOptions options;
  options.token = kToken;
  ControlApi http(
      {&rack},
      [&](std::function<void()> f) {
        ++posted;
        f();  // the test thread stands in for the device thread
      },
      options);
  const uint16_t port = http.listen(0);
  ASSERT_GT(port, 0);
  const std::string auth = "Authorization: Bearer " + kToken + "\r\n";
  const std::string unplug = R"({"rim": 2})";
  struct Case {
    std::string request;
    int status;
  };
  const std::string p = std::to_string(port);
  const std::vector<Case> refused = {
      {http_request(port, "POST", "/api/rim/unplug", unplug, ""), 401},
      {http_request(port, "POST", "/api/rim/unplug", unplug, "Authorization: Bearer 0123\r\n"),
       401},
      {http_request(port, "POST", "/api/rim/unplug", unplug,
                    "Authorization: Bearer " + kToken.substr(0, 31) + "0\r\n"),
       401},
      {"POST /api/rim/unplug HTTP/1.1\r\nHost: attacker.example:" + p + "\r\n" + auth +
           "Content-Type: application/json\r\nContent-Length: 10\r\n\r\n" + unplug,
       403},
      {http_request(port, "POST", "/api/rim/unplug", unplug,
                    auth + "Origin: http://attacker.example\r\n"),
       403},
      {http_request(port, "POST", "/api/rim/unplug", unplug, auth, "text/plain"), 415},
      {http_request(port, "PUT", "/api/rim/unplug", unplug, auth), 405},
      {http_request(port, "POST", "/api/rim/unplug", std::string(70000, ' '), auth), 413},
  };
  for (const Case& c : refused) {
    const std::string answer = http_exchange(port, c.request);
    EXPECT_EQ(status_of(answer), c.status) << c.request.substr(0, 200) << "\n" << answer;
    EXPECT_EQ(answer.find("Access-Control-Allow"), std::string::npos) << "no CORS headers";
  }
  EXPECT_EQ(posted, 0);
  EXPECT_EQ(rack.rims().at(2).state, RimState::Online);
  // The same request, properly made, is served; localhost and the own Origin are fine.
  EXPECT_EQ(status_of(http_exchange(port, http_request(port, "GET", "/api/esm", "", auth))), 200);
  const std::string ok = http_exchange(
      port, "POST /api/rim/unplug HTTP/1.1\r\nHost: localhost:" + p +
                "\r\nOrigin: http://localhost:" + p + "\r\n" + auth +
                "Content-Type: application/json; charset=utf-8\r\nContent-Length: 10\r\n\r\n" +
                unplug);
  EXPECT_EQ(status_of(ok), 200) << ok;
  EXPECT_EQ(rack.rims().at(2).state, RimState::Offline);
  EXPECT_EQ(posted, 2);
  // A wrong method on a known endpoint: 405 with the accepted one in Allow (RFC 9110 §15.5.6).
  const std::string wrong =
      http_exchange(port, http_request(port, "GET", "/api/rim/unplug", "", auth));
  EXPECT_EQ(status_of(wrong), 405) << wrong;
  EXPECT_NE(wrong.find("Allow: POST"), std::string::npos) << wrong;
  EXPECT_NE(wrong.find("{"), std::string::npos) << "a JSON body with the reason";
  // Every slave of the segment is reachable; an unknown one is 404.
  EXPECT_EQ(
      status_of(http_exchange(port, http_request(port, "GET", "/api/slaves/0/esm", "", auth))),
      200);
  EXPECT_EQ(
      status_of(http_exchange(port, http_request(port, "GET", "/api/slaves/1/esm", "", auth))),
      404);
  http.stop();
}

// Item 4: the port is ours alone.
TEST_F(ControlApiTest, ASecondListenerOnTheSamePortIsRefused) {
  ControlApiOptions options;
  options.token = kToken;
  ControlApi first({&rack}, nullptr, options);
  const uint16_t port = first.listen(0);
  ControlApi second({&rack}, nullptr, options);
  EXPECT_THROW(second.listen(port), std::runtime_error);
  first.stop();
}

// Item 3: slow clients are cut off at the request deadline; a legitimate request is served
// meanwhile; a huge announced body is refused before it is read.
TEST_F(ControlApiTest, SlowClientsCannotStarveTheApi) {
  ControlApiOptions options;
  options.token = kToken;
  options.limits.request_deadline = std::chrono::milliseconds(800);
  ControlApi http({&rack}, nullptr, options);
  const uint16_t port = http.listen(0);
  std::vector<int> slow;
  for (int i = 0; i < 40; ++i) {
    const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(port);
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    ASSERT_EQ(::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
    (void)!::send(fd, "GET /api/esm HTTP/1.1\r\nHo", 25, MSG_NOSIGNAL);
    slow.push_back(fd);
  }
  const auto t0 = std::chrono::steady_clock::now();
  const std::string answer = http_exchange(
      port, http_request(port, "GET", "/api/esm", "", "Authorization: Bearer " + kToken + "\r\n"));
  EXPECT_EQ(status_of(answer), 200);
  EXPECT_LT(std::chrono::steady_clock::now() - t0, std::chrono::milliseconds(500));
  // Trickling one byte at a time does not extend the deadline.
  for (int k = 0; k < 12; ++k) {
    for (int fd : slow) (void)!::send(fd, "s", 1, MSG_NOSIGNAL);
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  EXPECT_GE(http.timed_out_requests(), 40u);
  for (int fd : slow) ::close(fd);
  http.stop();
}

// Item 3: a 503 means nothing changed: a command the device thread did not take in time is
// withdrawn and skipped when the device thread gets to it.
TEST_F(ControlApiTest, ACommandNotTakenInTimeIsWithdrawn) {
  std::vector<std::function<void()>> parked;
  ControlApiOptions options;
  options.token = kToken;
  options.answer_timeout = std::chrono::milliseconds(50);
  ControlApi http(
      {&rack}, [&](std::function<void()> f) { parked.push_back(std::move(f)); }, options);
  auto r = http.handle("POST", "/api/rim/unplug", R"({"rim": 2})");
  EXPECT_EQ(r.status, 503);
  EXPECT_NE(r.body["error"].get<std::string>().find("nothing changed"), std::string::npos);
  ASSERT_EQ(parked.size(), 1u);
  parked.front()();  // the device thread comes back
  EXPECT_EQ(rack.rims().at(2).state, RimState::Online);
}

// Items 1 and 8: files named by a request are read below --data-dir only, and an error never
// quotes their content.
TEST_F(ControlApiTest, ReplayFilesAreReadBelowTheDataDirectoryOnly) {
  namespace fs = std::filesystem;
  const fs::path root = fs::path(::testing::TempDir()) / "control_api_data";
  fs::remove_all(root);
  fs::create_directories(root / "data");
  { std::ofstream(root / "data" / "ok.csv") << "0,1\n1,2\n"; }
  { std::ofstream(root / "secret") << "root:SECRET-HASH:0:0\n"; }
  fs::create_symlink(root / "secret", root / "data" / "link.csv");
  { std::ofstream(root / "data" / "bad.csv") << "0,1\nSECRET-LINE\n"; }
  ControlApiOptions options;
  options.token = kToken;
  options.data = mdp::FileRoot::open((root / "data").string());
  ControlApi http({&rack}, nullptr, options);
  const uint16_t n = at(1, 12).module().number;  // an analog input card
  auto replay = [&](const std::string& file) {
    return http.handle(
        "POST", "/api/channel",
        json{{"module", n}, {"channel", 0}, {"source", "replay"}, {"params", {{"file", file}}}}
            .dump());
  };
  EXPECT_EQ(replay("ok.csv").status, 200);
  for (const std::string& file : std::vector<std::string>{"/etc/shadow", "../secret", "link.csv",
                                                          (root / "secret").string(), "bad.csv"}) {
    const auto r = replay(file);
    EXPECT_EQ(r.status, 400) << file;
    EXPECT_EQ(r.body.dump().find("SECRET"), std::string::npos) << r.body.dump();
  }
  fs::remove_all(root);
}
