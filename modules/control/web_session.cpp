#include "modules/control/web_session.hpp"

#include <cstdint>
#include <utility>

namespace rackcat::modules {

bool same_secret(std::string_view given, std::string_view expected) {
  if (expected.empty()) return false;
  unsigned diff = given.size() == expected.size() ? 0u : 1u;
  for (size_t i = 0; i < expected.size(); ++i) {
    diff |= static_cast<unsigned>(static_cast<uint8_t>(i < given.size() ? given[i] : 0) ^
                                  static_cast<uint8_t>(expected[i]));
  }
  return diff == 0;
}

WebSession::WebSession(std::string token, std::string session)
    : token_(std::move(token)), session_(std::move(session)) {}

namespace {

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

// The value of `name` in an application/x-www-form-urlencoded query (the secret is hex, so
// no percent-decoding is needed: a percent-encoded secret simply does not match).
std::string_view query_value(std::string_view query, std::string_view name) {
  while (!query.empty()) {
    const size_t amp = query.find('&');
    const std::string_view pair = query.substr(0, amp);
    const size_t eq = pair.find('=');
    if (eq != std::string_view::npos && pair.substr(0, eq) == name) return pair.substr(eq + 1);
    if (amp == std::string_view::npos) break;
    query.remove_prefix(amp + 1);
  }
  return {};
}

HttpResponse text_response(int status, std::string body) {
  HttpResponse r;
  r.status = status;
  r.content_type = "text/plain; charset=utf-8";
  r.body = std::move(body);
  return r;
}

}  // namespace

HttpResponse WebSession::login(const HttpRequest& request) const {
  if (!same_secret(query_value(request.query, "token"), token_)) {
    return text_response(401,
                         "wrong or missing login secret: open the login URL rackcat run printed\n");
  }
  HttpResponse r = text_response(303, "logged in\n");
  r.headers.emplace_back("Location", "/");
  // No Max-Age: the cookie ends with the browser session; the secret ends with the run.
  r.headers.emplace_back("Set-Cookie", std::string(kSessionCookie) + "=" + session_ +
                                           "; Path=/; HttpOnly; SameSite=Strict");
  r.headers.emplace_back("Referrer-Policy", "no-referrer");
  return r;
}

bool WebSession::has_session(const HttpRequest& request) const {
  // RFC 6265 §5.4: one Cookie header, "name=value" pairs separated by "; ".
  for (const auto& [name, value] : request.headers) {
    if (name != "cookie") continue;
    std::string_view rest = value;
    while (!rest.empty()) {
      const size_t semi = rest.find(';');
      const std::string_view pair = trim(rest.substr(0, semi));
      const size_t eq = pair.find('=');
      if (eq != std::string_view::npos && pair.substr(0, eq) == kSessionCookie &&
          same_secret(pair.substr(eq + 1), session_)) {
        return true;
      }
      if (semi == std::string_view::npos) break;
      rest.remove_prefix(semi + 1);
    }
  }
  return false;
}

std::string WebSession::login_url(uint16_t port, std::string_view token) {
  return "http://127.0.0.1:" + std::to_string(port) + std::string(kLoginPath) +
         "?token=" + std::string(token);
}

}  // namespace rackcat::modules
