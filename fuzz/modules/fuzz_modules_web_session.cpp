// libFuzzer target of the web page's credential parsing (modules::WebSession: the Cookie header,
// RFC 6265 §5.4, and the login URL's query). Input: "COOKIE\nQUERY" (a missing line is
// empty). Invariants: the session is accepted only when the Cookie header holds the exact
// pair rackcat_session=<session>; the login succeeds (303 + Set-Cookie) only when the query
// holds token=<token>; otherwise 401 and no cookie. A crash or sanitizer report is a bug.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>

#include "modules/control/web_session.hpp"

namespace {

constexpr std::string_view kToken = "0123456789abcdef0123456789abcdef";
constexpr std::string_view kSession = "fedcba9876543210fedcba9876543210";

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const rackcat::modules::WebSession session{std::string(kToken), std::string(kSession)};
  const std::string_view input(reinterpret_cast<const char*>(data), size);
  const size_t nl = input.find('\n');
  const std::string_view cookie = input.substr(0, nl);
  const std::string_view query =
      nl == std::string_view::npos ? std::string_view() : input.substr(nl + 1);

  rackcat::modules::HttpRequest req;
  req.method = "GET";
  req.path = "/login";
  req.query = std::string(query);
  req.headers.emplace_back("cookie", std::string(cookie));

  const bool has = session.has_session(req);
  if (has && cookie.find("rackcat_session=" + std::string(kSession)) == std::string_view::npos) {
    std::abort();  // accepted without the exact pair
  }
  const rackcat::modules::HttpResponse r = session.login(req);
  const bool logged_in = r.status == 303;
  if (logged_in && query.find("token=" + std::string(kToken)) == std::string_view::npos) {
    std::abort();
  }
  if (!logged_in && r.status != 401) std::abort();
  bool sets_cookie = false;
  for (const auto& [k, v] : r.headers) sets_cookie = sets_cookie || k == "Set-Cookie";
  if (sets_cookie != logged_in) std::abort();
  return 0;
}
