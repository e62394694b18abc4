// Fault-injection and inspection API of the emulated racks: HTTP + JSON on 127.0.0.1
// (modules/control/http_server.hpp: deadlines and size caps no client can outlast).
//
// Who may call it: a request must carry the per-run secret (`Authorization: Bearer TOKEN`,
// the token `rackcat run` writes to STATE/control-token, mode 0600, for its own user), name
// the API's own origin in Host (127.0.0.1:PORT or localhost:PORT: a DNS-rebinding page has
// another), carry no foreign Origin, and send its body as application/json (a cross-site
// "simple" POST is text/plain). No CORS header is ever sent. These checks happen before one
// byte of the body is read. Refusals: 401, 403, 405, 411, 413, 415; bad requests 400/404.
//
// What runs where: the request is parsed and validated on the API's worker thread, files it
// names (a replay recording) are read there too, below `--data-dir` only; the device thread
// receives one prepared command through the post function and applies it between two
// cycles. At most kMaxInFlight commands wait for the device thread (more: 503 at once); a
// command the device thread has not taken within the answer timeout is withdrawn and the
// answer is 503 "nothing changed"; once taken, the client waits for its real result. So a 5xx
// always means nothing changed.
//
// The web page (docs/WEB.md): `/` and its assets, GET /login?token=SECRET (sets the session
// cookie, modules/control/web_session.hpp) and GET /api/stream (server-sent snapshots,
// modules/control/live_snapshot.hpp). Either credential opens everything; a request with the
// cookie must also name our own Origin when it is a POST.
//
// `/api/...` addresses slave 0; `/api/slaves/N/...` slave N of the segment; GET /api/slaves
// lists them. A slave of a line that is not a rack (modules/control/io_device.hpp) has
// GET /api/io (its outputs and inputs) and POST /api/io/inputs only. The endpoints are listed in
// docs/MODULES.md "Control API"; `rackcat ctl` is the command-line client.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <utility>

#include <chrono>
#include <vector>

#include "modules/control/http_server.hpp"
#include "modules/control/io_device.hpp"
#include "modules/control/live_snapshot.hpp"
#include "modules/control/web_session.hpp"
#include "modules/rack/rack.hpp"

namespace rackcat::mdp {
class FileRoot;
}

namespace rackcat::modules {

inline constexpr uint16_t kDefaultControlPort = 8765;
// Files in the state directory: the secret (mode 0600) and the port (with --control-port 0).
inline constexpr const char* kTokenFileName = "control-token";
inline constexpr const char* kPortFileName = "control-port";

struct ControlApiOptions {
  std::string token;  // the Bearer secret; listen() refuses to start without one
  // Where replay files named by requests are read; null: such requests are refused.
  std::shared_ptr<const mdp::FileRoot> data;
  HttpLimits limits;
  std::chrono::milliseconds answer_timeout{2000};
  // The ESC side of each slave for the web page's line view (device thread, no allocation);
  // null: those fields stay 0.
  SlaveLinkFn link;
  // How often GET /api/stream sends a snapshot (the page wants >= 10 per second).
  std::chrono::milliseconds stream_period{50};
};

// One slave of the segment: a rack, or another device of the line.
struct ControlSlave {
  Rack* rack = nullptr;
  IoDevice* io = nullptr;
};

class ControlApi {
 public:
  // bugprone-exception-escape false positive (clang-tidy 14): its ExceptionAnalyzer looks into
  // the bodies of nlohmann::json's noexcept move constructor and destructor and ignores their
  // noexcept (llvm-project#54956); Response's implicit members throw nothing.
  // NOLINTNEXTLINE(bugprone-exception-escape)
  struct Response {
    // The same false positive on the defaulted constructor (nlohmann::json's members).
    // NOLINTNEXTLINE(bugprone-exception-escape)
    Response() = default;
    Response(int status_code, nlohmann::json json_body, std::string allowed = {})
        : status(status_code), body(std::move(json_body)), allow(std::move(allowed)) {}

    int status = 200;
    nlohmann::json body;
    // With 405: the methods the endpoint accepts, sent as the Allow header (RFC 9110 §15.5.6).
    std::string allow;
  };

  static constexpr int kMaxInFlight = 8;
  // Open event streams (each holds one HTTP worker); more are answered 503.
  static constexpr int kMaxStreams = 2;

  // One rack (tests, fuzzing): no post function = commands run on the calling thread.
  ControlApi(Rack& rack, PostFn post);
  // The racks of a segment, slave 0 first.
  ControlApi(const std::vector<Rack*>& racks, PostFn post, ControlApiOptions options);
  // The slaves of a line in line order (each exactly one of rack, io).
  ControlApi(std::vector<ControlSlave> slaves, PostFn post, ControlApiOptions options);
  ~ControlApi();

  // Binds 127.0.0.1:port exclusively (0 = any free port) and serves; returns the port. Throws
  // std::runtime_error when the port is taken or no token is set.
  uint16_t listen(uint16_t port);
  void stop();

  // One request without the HTTP checks (tests, fuzzing): parsed, then the command executed
  // through the post function (or on the calling thread without one).
  Response handle(std::string_view method, std::string_view path, std::string_view body);
  // One HTTP request with every check: what the server runs on its worker threads.
  HttpResponse serve(const HttpRequest& request);
  // The checks made once the header is complete, before the body is read: Host, Origin,
  // authentication, method, Content-Type. nullopt: go on.
  std::optional<HttpResponse> check_head(const HttpRequest& request) const;

  // Requests the server cut off at their deadline (slow clients).
  uint64_t timed_out_requests() const { return server_ ? server_->timed_out() : 0; }
  // A fresh secret: 128 random bits (getrandom(2)) as 32 hex digits.
  static std::string new_token();
  // The URL that logs a browser in (printed once by `rackcat run`).
  std::string login_url() const { return WebSession::login_url(port_, options_.token); }

 private:
  using Command = std::function<Response()>;
  struct Prepared {
    std::optional<Response> answer;  // decided without the device (an error, a listing)
    Command command;                 // else: run on the device thread
  };
  Prepared prepare(std::string_view method, std::string_view path, std::string_view body);
  Prepared dispatch(Rack& rack, std::string_view method, std::string_view path,
                    const nlohmann::json& body);
  Prepared dispatch_io(size_t slave, IoDevice& io, std::string_view method, std::string_view path,
                       const nlohmann::json& body);
  Response execute(Command command);
  HttpResponse serve_page(const HttpRequest& request) const;
  HttpResponse open_stream();

  std::vector<ControlSlave> slaves_;
  PostFn post_;
  ControlApiOptions options_;
  uint16_t port_ = 0;
  std::unique_ptr<HttpServer> server_;
  std::shared_ptr<std::atomic<bool>> alive_;
  std::atomic<int> in_flight_{0};
  WebSession session_;
  std::vector<Rack*> racks_;  // per slave: its rack, or null for another device (the stream)
  std::shared_ptr<std::atomic<int>> streams_ = std::make_shared<std::atomic<int>>(0);
};

}  // namespace rackcat::modules
