// Fault-injection and inspection API of the emulated rack: HTTP + JSON (cpp-httplib) bound
// to 127.0.0.1 only. Every request is executed on the device thread through the post
// function, so it sees and changes the rack between two cycles; the HTTP thread waits for
// the answer (2 s, then 503). Invalid requests get 4xx and {"error": "<reason>"}, and change
// nothing. The endpoints are listed in docs/MODULES.md "Control API"; `rackcat ctl` is the
// command-line client.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <thread>

#include "modules/rack/rack.hpp"

namespace httplib {
class Server;
}

namespace rackcat::modules {

inline constexpr uint16_t kDefaultControlPort = 8765;

class ControlApi {
 public:
  // bugprone-exception-escape false positive (clang-tidy 14): its ExceptionAnalyzer looks into
  // the bodies of nlohmann::json's noexcept move constructor and destructor and ignores their
  // noexcept (llvm-project#54956); Response's implicit members throw nothing.
  // NOLINTNEXTLINE(bugprone-exception-escape)
  struct Response {
    int status = 200;
    nlohmann::json body;
  };

  ControlApi(Rack& rack, PostFn post);
  ~ControlApi();

  // Binds 127.0.0.1:port (0 = any free port) and serves on a thread; returns the port.
  // Throws std::runtime_error when the port cannot be bound.
  uint16_t listen(uint16_t port);
  void stop();

  // One request, executed on the calling thread (the device thread).
  Response handle(std::string_view method, std::string_view path, std::string_view body);

 private:
  Response dispatch(std::string_view method, std::string_view path, const nlohmann::json& body);

  Rack& rack_;
  PostFn post_;
  std::unique_ptr<httplib::Server> server_;
  std::thread thread_;
  std::shared_ptr<std::atomic<bool>> alive_;
};

}  // namespace rackcat::modules
