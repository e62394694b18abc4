// HTTP/1.1 server of the control API (see http_server.hpp). Message syntax per RFC 9112 §2-§6:
// request line, header fields up to the empty line, a body of Content-Length bytes.
#include "modules/control/http_server.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <memory>
#include <stdexcept>

#include "base/real_time.hpp"

namespace rackcat::modules {
namespace {

using Clock = std::chrono::steady_clock;

const char* reason_phrase(int status) {
  switch (status) {
    case 200:
      return "OK";
    case 303:
      return "See Other";
    case 400:
      return "Bad Request";
    case 401:
      return "Unauthorized";
    case 403:
      return "Forbidden";
    case 404:
      return "Not Found";
    case 405:
      return "Method Not Allowed";
    case 408:
      return "Request Timeout";
    case 411:
      return "Length Required";
    case 413:
      return "Content Too Large";
    case 415:
      return "Unsupported Media Type";
    case 421:
      return "Misdirected Request";
    case 431:
      return "Request Header Fields Too Large";
    case 500:
      return "Internal Server Error";
    case 503:
      return "Service Unavailable";
    default:
      return "Status";
  }
}

HttpResponse error_response(int status, std::string_view message) {
  HttpResponse r;
  r.status = status;
  r.body = "{\"error\": \"";
  r.body += message;  // fixed texts of this file only: no escaping needed
  r.body += "\"}\n";
  return r;
}

std::string lower(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

// Parses the request line and header fields (without the final empty line). False: malformed.
bool parse_head(std::string_view head, HttpRequest& req) {
  const size_t eol = head.find("\r\n");
  const std::string_view line = head.substr(0, eol);
  const size_t sp1 = line.find(' ');
  const size_t sp2 = line.rfind(' ');
  if (sp1 == std::string_view::npos || sp2 == sp1) return false;
  req.method = std::string(line.substr(0, sp1));
  std::string_view target = line.substr(sp1 + 1, sp2 - sp1 - 1);
  const std::string_view version = line.substr(sp2 + 1);
  if (version != "HTTP/1.1" && version != "HTTP/1.0") return false;
  if (target.empty() || target.front() != '/') return false;
  if (const size_t q = target.find('?'); q != std::string_view::npos) {
    req.query = std::string(target.substr(q + 1));
    target = target.substr(0, q);
  }
  req.path = std::string(target);
  size_t pos = eol == std::string_view::npos ? head.size() : eol + 2;
  while (pos < head.size()) {
    size_t end = head.find("\r\n", pos);
    if (end == std::string_view::npos) end = head.size();
    const std::string_view field = head.substr(pos, end - pos);
    const size_t colon = field.find(':');
    if (colon == std::string_view::npos || colon == 0) return false;
    const std::string_view name = field.substr(0, colon);
    if (name.find_first_of(" \t") != std::string_view::npos) return false;  // RFC 9112 §5.1
    req.headers.emplace_back(lower(name), std::string(trim(field.substr(colon + 1))));
    pos = end + 2;
  }
  return true;
}

bool send_all(int fd, const std::string& data) {
  size_t done = 0;
  while (done < data.size()) {
    const ssize_t n = ::send(fd, data.data() + done, data.size() - done, MSG_NOSIGNAL);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    done += static_cast<size_t>(n);
  }
  return true;
}

}  // namespace

std::optional<std::string_view> HttpRequest::header(std::string_view name) const {
  for (const auto& [k, v] : headers) {
    if (k == name) return std::string_view(v);
  }
  return std::nullopt;
}

struct HttpServer::Connection {
  int fd = -1;
  Clock::time_point deadline;
  std::string buffer;
  bool have_head = false;
  size_t body_length = 0;
  HttpRequest request;
};

std::string HttpServer::serialize(const HttpResponse& r) {
  std::string out = "HTTP/1.1 " + std::to_string(r.status) + " " + reason_phrase(r.status) + "\r\n";
  out += "Content-Type: " + r.content_type + "\r\n";
  if (!r.next_event) out += "Content-Length: " + std::to_string(r.body.size()) + "\r\n";
  out += "Cache-Control: no-store\r\nX-Content-Type-Options: nosniff\r\nConnection: close\r\n";
  for (const auto& [k, v] : r.headers) {
    out += k;
    out += ": ";
    out += v;
    out += "\r\n";
  }
  out += "\r\n";
  out += r.body;
  return out;
}

std::string HttpServer::serialize_stream_head(const HttpResponse& r) {
  std::string head = serialize(r);  // ends with the empty line and r.body (empty)
  head.resize(head.size() - r.body.size());
  return head;
}

void HttpServer::stream_events(int fd, const HttpResponse& r) {
  if (!send_all(fd, serialize_stream_head(r))) return;
  std::string event;
  for (;;) {
    event.clear();
    if (!r.next_event(event)) return;
    if (!event.empty() && !send_all(fd, event)) return;  // the client went away
    std::unique_lock lock(mutex_);
    if (stop_cv_.wait_for(lock, r.event_period, [this] { return stopping_.load(); })) return;
  }
}

HttpServer::HttpServer(HttpLimits limits, HeadCheck head_check, Handler handler)
    : limits_(limits), head_check_(std::move(head_check)), handler_(std::move(handler)) {}

HttpServer::~HttpServer() {
  stop();
}

uint16_t HttpServer::listen(uint16_t port) {
  listen_fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (listen_fd_ < 0) throw std::runtime_error(std::string("socket: ") + std::strerror(errno));
  // SO_REUSEADDR only: a restart may bind while old connections linger in TIME_WAIT, but a
  // second listener on the same port is refused (that needs SO_REUSEPORT, never set here).
  const int one = 1;
  ::setsockopt(listen_fd_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof(one));
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(port);
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::bind(listen_fd_, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)) != 0 ||
      ::listen(listen_fd_, 64) != 0) {
    const int err = errno;
    ::close(listen_fd_);
    listen_fd_ = -1;
    throw std::runtime_error("cannot listen on 127.0.0.1:" + std::to_string(port) + ": " +
                             std::strerror(err));
  }
  socklen_t len = sizeof(addr);
  ::getsockname(listen_fd_, reinterpret_cast<sockaddr*>(&addr), &len);
  wake_fd_ = ::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
  io_ = std::thread([this] { io_loop(); });
  for (size_t i = 0; i < limits_.workers; ++i) workers_.emplace_back([this] { worker_loop(); });
  return ntohs(addr.sin_port);
}

void HttpServer::stop() {
  if (stopping_.exchange(true)) return;
  if (wake_fd_ >= 0) {
    const uint64_t v = 1;
    (void)!::write(wake_fd_, &v, sizeof(v));
  }
  {
    const std::lock_guard lock(mutex_);  // a stream between its check and its wait sees it
  }
  cv_.notify_all();
  stop_cv_.notify_all();
  if (io_.joinable()) io_.join();
  for (auto& w : workers_) w.join();
  workers_.clear();
  for (auto& [fd, req] : queue_) ::close(fd);
  queue_.clear();
  if (listen_fd_ >= 0) ::close(listen_fd_);
  if (wake_fd_ >= 0) ::close(wake_fd_);
  listen_fd_ = wake_fd_ = -1;
}

void HttpServer::answer_and_close(int fd, const HttpResponse& r) {
  // Best effort on a non-blocking socket: the answers sent from here are a few hundred bytes.
  const std::string out = serialize(r);
  (void)!::send(fd, out.data(), out.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
  ::shutdown(fd, SHUT_WR);
  ::close(fd);
}

bool HttpServer::on_readable(Connection& c) {
  char buf[4096];
  for (;;) {
    const ssize_t n = ::recv(c.fd, buf, sizeof buf, MSG_DONTWAIT);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) return true;
    if (n <= 0) {
      ::close(c.fd);  // closed or failed before a complete request
      return false;
    }
    c.buffer.append(buf, static_cast<size_t>(n));
    if (!c.have_head) {
      const size_t end = c.buffer.find("\r\n\r\n");
      if (end == std::string::npos) {
        if (c.buffer.size() > limits_.max_header_bytes) {
          answer_and_close(c.fd, error_response(431, "request header too large"));
          return false;
        }
        continue;
      }
      if (end > limits_.max_header_bytes) {
        answer_and_close(c.fd, error_response(431, "request header too large"));
        return false;
      }
      if (!parse_head(std::string_view(c.buffer).substr(0, end), c.request)) {
        answer_and_close(c.fd, error_response(400, "malformed request"));
        return false;
      }
      c.buffer.erase(0, end + 4);
      c.have_head = true;
      if (c.request.header("transfer-encoding")) {
        answer_and_close(c.fd, error_response(411, "send the body with a Content-Length"));
        return false;
      }
      if (const auto cl = c.request.header("content-length")) {
        size_t v = 0;
        if (cl->empty() || cl->size() > 12 ||
            !std::all_of(cl->begin(), cl->end(), [](char ch) { return ch >= '0' && ch <= '9'; })) {
          answer_and_close(c.fd, error_response(400, "bad Content-Length"));
          return false;
        }
        for (char ch : *cl) v = v * 10 + static_cast<size_t>(ch - '0');
        c.body_length = v;
      }
      if (auto refused = head_check_ ? head_check_(c.request) : std::nullopt) {
        answer_and_close(c.fd, *refused);
        return false;
      }
      if (c.body_length > limits_.max_body_bytes) {
        answer_and_close(c.fd, error_response(413, "request body larger than 65536 bytes"));
        return false;
      }
    }
    if (c.have_head && c.buffer.size() >= c.body_length) {
      c.request.body = c.buffer.substr(0, c.body_length);
      {
        std::lock_guard lock(mutex_);
        if (queue_.size() >= limits_.max_queued) {
          answer_and_close(c.fd, error_response(503, "too many requests in progress"));
          return false;
        }
        queue_.emplace_back(c.fd, std::move(c.request));
      }
      cv_.notify_one();
      return false;
    }
  }
}

void HttpServer::io_loop() {
  (void)base::leave_real_time();  // a helper thread, not the device thread
  std::vector<std::unique_ptr<Connection>> conns;
  std::vector<pollfd> fds;
  while (!stopping_.load()) {
    const auto now = Clock::now();
    // Deadlines: the whole request must have arrived in time, however it trickles in.
    for (auto it = conns.begin(); it != conns.end();) {
      if ((*it)->deadline <= now) {
        ++timed_out_;
        answer_and_close((*it)->fd, error_response(408, "request not complete in time"));
        it = conns.erase(it);
      } else {
        ++it;
      }
    }
    int timeout_ms = 1000;
    for (const auto& c : conns) {
      const auto left =
          std::chrono::duration_cast<std::chrono::milliseconds>(c->deadline - now).count();
      timeout_ms =
          static_cast<int>(std::min<long long>(timeout_ms, std::max<long long>(left, 0) + 1));
    }
    fds.clear();
    fds.push_back({listen_fd_, POLLIN, 0});
    fds.push_back({wake_fd_, POLLIN, 0});
    for (const auto& c : conns) fds.push_back({c->fd, POLLIN, 0});
    const int ready = ::poll(fds.data(), fds.size(), timeout_ms);
    if (ready < 0) {
      if (errno == EINTR) continue;
      break;
    }
    if (fds[1].revents) break;
    // Existing connections first (their indices match fds[2..]).
    std::vector<std::unique_ptr<Connection>> keep;
    keep.reserve(conns.size());
    for (size_t i = 0; i < conns.size(); ++i) {
      if (fds[i + 2].revents & (POLLIN | POLLHUP | POLLERR)) {
        if (!on_readable(*conns[i])) continue;
      }
      keep.push_back(std::move(conns[i]));
    }
    conns.swap(keep);
    if (fds[0].revents & POLLIN) {
      for (;;) {
        const int fd = ::accept4(listen_fd_, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
        if (fd < 0) break;
        if (conns.size() >= limits_.max_connections) {
          ++refused_connections_;
          answer_and_close(fd, error_response(503, "too many open connections"));
          continue;
        }
        auto c = std::make_unique<Connection>();
        c->fd = fd;
        c->deadline = Clock::now() + limits_.request_deadline;
        conns.push_back(std::move(c));
      }
    }
  }
  for (auto& c : conns) ::close(c->fd);
}

void HttpServer::worker_loop() {
  (void)base::leave_real_time();  // a helper thread, not the device thread
  for (;;) {
    std::pair<int, HttpRequest> job;
    {
      std::unique_lock lock(mutex_);
      cv_.wait(lock, [this] { return stopping_.load() || !queue_.empty(); });
      if (stopping_.load()) return;
      job = std::move(queue_.front());
      queue_.pop_front();
    }
    HttpResponse r;
    try {
      r = handler_(job.second);
    } catch (const std::exception&) {
      r = error_response(500, "internal error");
    }
    // The socket becomes blocking with a send timeout: a client that does not read its answer
    // holds this worker at most 1 s.
    const int flags = ::fcntl(job.first, F_GETFL);
    ::fcntl(job.first, F_SETFL, flags & ~O_NONBLOCK);
    timeval tv{1, 0};
    ::setsockopt(job.first, SOL_SOCKET, SO_SNDTIMEO, &tv, sizeof(tv));
    if (r.next_event) {
      stream_events(job.first, r);
    } else {
      send_all(job.first, serialize(r));
    }
    ::shutdown(job.first, SHUT_WR);
    ::close(job.first);
  }
}

}  // namespace rackcat::modules
