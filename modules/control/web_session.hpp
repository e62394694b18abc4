// The browser credential of the control API's web page. `rackcat run` prints a login URL
// carrying the run's secret (http://127.0.0.1:PORT/login?token=SECRET); opening it sets a
// session cookie (RFC 6265 §4.1: HttpOnly, so no script reads it; SameSite=Strict, so no other
// site's page makes the browser send it, RFC 6265bis §5.4.7) whose value is a second random
// secret of this run, never the token itself. Requests then carry either the Bearer token
// (ctl, scripts) or this cookie (the page).
#pragma once

#include <string>
#include <string_view>

#include "modules/control/http_server.hpp"

namespace rackcat::modules {

inline constexpr std::string_view kSessionCookie = "rackcat_session";
inline constexpr std::string_view kLoginPath = "/login";

class WebSession {
 public:
  // token: the run's secret the login URL must carry; session: the cookie's value.
  WebSession(std::string token, std::string session);

  // GET /login?token=SECRET: 303 to "/" with the cookie, or 401 for a missing/wrong secret.
  HttpResponse login(const HttpRequest& request) const;
  // True when the request's Cookie header (RFC 6265 §5.4) names the session cookie with this
  // run's value.
  bool has_session(const HttpRequest& request) const;
  // The login URL `rackcat run` prints.
  static std::string login_url(uint16_t port, std::string_view token);

 private:
  std::string token_;
  std::string session_;
};

// Constant time in the length of `expected`: the comparison does not tell how much matched.
bool same_secret(std::string_view given, std::string_view expected);

}  // namespace rackcat::modules
