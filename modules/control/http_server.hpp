// The control API's HTTP/1.1 server (RFC 9112 message syntax, one request per connection),
// built so that no client can starve it or grow it: one I/O thread multiplexes every
// connection with poll(2) and enforces a deadline for the whole request (a client that sends
// its header one byte at a time is cut off when the deadline passes, not when it stops), a
// cap on header and body bytes and on open connections; complete requests go to a small
// bounded pool of worker threads. Bodies are framed by Content-Length only (chunked uploads
// are refused with 411). The listening socket is exclusive: no SO_REUSEPORT, so a second
// process cannot bind the same port.
//
// Every request is first shown to the head check, once its header is complete and before one
// byte of its body is read: authentication, Host, Origin and Content-Type are decided there,
// so a refused request costs nothing whatever body it announces.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <thread>
#include <utility>
#include <vector>

namespace rackcat::modules {

struct HttpRequest {
  std::string method;
  std::string path;                                          // the request target without its query
  std::string query;                                         // after '?', empty when none
  std::vector<std::pair<std::string, std::string>> headers;  // names in lower case
  std::string body;
  // The first header named `name` (lower case), or nullopt.
  std::optional<std::string_view> header(std::string_view name) const;
};

struct HttpResponse {
  int status = 200;
  std::string content_type = "application/json";
  std::string body;
  std::vector<std::pair<std::string, std::string>> headers;  // extra headers
  // A server-sent event stream (WHATWG HTML §9.2) instead of a body: after the header the
  // worker calls next_event every event_period and sends what it appends to the string, until
  // it returns false, the client goes away or the server stops. The stream holds its worker.
  std::function<bool(std::string&)> next_event;
  std::chrono::milliseconds event_period{100};
};

struct HttpLimits {
  size_t max_header_bytes = 8 * 1024;
  size_t max_body_bytes = 64 * 1024;
  size_t max_connections = 64;  // open connections; more are answered 503 and closed
  std::chrono::milliseconds request_deadline{3000};  // from accept to the last body byte
  size_t workers = 4;
  size_t max_queued = 16;  // complete requests waiting for a worker; more are answered 503
};

class HttpServer {
 public:
  using HeadCheck = std::function<std::optional<HttpResponse>(const HttpRequest&)>;
  using Handler = std::function<HttpResponse(const HttpRequest&)>;

  HttpServer(HttpLimits limits, HeadCheck head_check, Handler handler);
  ~HttpServer();
  HttpServer(const HttpServer&) = delete;
  HttpServer& operator=(const HttpServer&) = delete;

  // Binds 127.0.0.1:port exclusively (0 = any free port), starts the threads and returns the
  // port. Throws std::runtime_error naming the port and the reason ("address in use").
  uint16_t listen(uint16_t port);
  void stop();

  // Counters for tests and the log.
  uint64_t refused_connections() const { return refused_connections_.load(); }
  uint64_t timed_out() const { return timed_out_.load(); }

  static std::string serialize(const HttpResponse& r);
  // The header of an event stream: no Content-Length, the body ends when the connection does.
  static std::string serialize_stream_head(const HttpResponse& r);

 private:
  struct Connection;
  void io_loop();
  void worker_loop();
  // Returns false when the connection is finished (answered or handed to a worker).
  bool on_readable(Connection& c);
  void answer_and_close(int fd, const HttpResponse& r);
  void stream_events(int fd, const HttpResponse& r);

  HttpLimits limits_;
  HeadCheck head_check_;
  Handler handler_;
  int listen_fd_ = -1;
  int wake_fd_ = -1;
  std::atomic<bool> stopping_{false};
  std::thread io_;
  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable cv_;
  std::condition_variable stop_cv_;  // wakes event streams when the server stops
  std::deque<std::pair<int, HttpRequest>> queue_;
  std::atomic<uint64_t> refused_connections_{0};
  std::atomic<uint64_t> timed_out_{0};
};

}  // namespace rackcat::modules
