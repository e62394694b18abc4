#include "modules/control/control_api.hpp"

#include <fmt/format.h>
#include <sys/random.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <condition_variable>
#include <initializer_list>
#include <mutex>
#include <stdexcept>

#include "mdp/diagnosis_catalogue.hpp"
#include "mdp/file_root.hpp"
#include "modules/cards/uart_driver.hpp"
#include "modules/control/web_assets.hpp"
#include "modules/signals/source_factory.hpp"

namespace rackcat::modules {
namespace {

using json = nlohmann::json;

struct BadRequest : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

const char* fault_name(WiringFault f) {
  switch (f) {
    case WiringFault::None:
      return "none";
    case WiringFault::ShortToGround:
      return "safe";
    case WiringFault::ShortToSupply:
      return "unsafe";
  }
  return "?";
}

double finite_or_zero(double v) {
  return std::isfinite(v) ? v : 0.0;
}

// Text that echoes request bytes (paths, file contents in parse errors) may not be UTF-8; a
// JSON answer must be. Anything outside printable ASCII becomes '?'.
std::string printable(std::string_view s) {
  std::string out(s.substr(0, 512));
  for (char& c : out) {
    if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) >= 0x7F) c = '?';
  }
  return out;
}

// Every key of a request body must be one the endpoint reads: a misspelt key is named as such
// (`{"valu": 1}` -> unknown field 'valu'), not reported as some other field missing.
void known_fields(const json& body, std::string_view path,
                  std::initializer_list<std::string_view> keys) {
  if (!body.is_object()) throw BadRequest("the request body must be a JSON object");
  for (auto it = body.begin(); it != body.end(); ++it) {
    if (std::find(keys.begin(), keys.end(), it.key()) != keys.end()) continue;
    std::string known;
    for (std::string_view k : keys) {
      if (!known.empty()) known += ", ";
      known += k;
    }
    throw BadRequest(fmt::format("unknown field '{}' ({} takes {})", printable(it.key()),
                                 printable(path), known));
  }
}

// Typed field access with precise errors.
const json& field(const json& body, const char* key) {
  if (!body.is_object()) throw BadRequest("the request body must be a JSON object");
  auto it = body.find(key);
  if (it == body.end()) throw BadRequest(fmt::format("missing field '{}'", key));
  return *it;
}
int64_t integer(const json& body, const char* key, int64_t lo, int64_t hi) {
  const json& v = field(body, key);
  if (!v.is_number_integer()) throw BadRequest(fmt::format("'{}' must be an integer", key));
  const auto x = v.get<int64_t>();
  if (x < lo || x > hi) throw BadRequest(fmt::format("'{}' must be {}..{}", key, lo, hi));
  return x;
}
double number(const json& body, const char* key) {
  const json& v = field(body, key);
  if (!v.is_number()) throw BadRequest(fmt::format("'{}' must be a number", key));
  return v.get<double>();
}
bool boolean(const json& body, const char* key, bool fallback) {
  if (!body.contains(key)) return fallback;
  const json& v = body.at(key);
  if (!v.is_boolean()) throw BadRequest(fmt::format("'{}' must be true or false", key));
  return v.get<bool>();
}
std::string text(const json& body, const char* key) {
  const json& v = field(body, key);
  if (!v.is_string()) throw BadRequest(fmt::format("'{}' must be a string", key));
  return v.get<std::string>();
}

json module_json(Rack& rack, const CardDriver& d) {
  const mdp::Module& m = d.module();
  json j{{"module", m.number},
         {"rim", m.rim},
         {"slot", m.slot},
         {"card", std::string(m.card->name)},
         {"description", std::string(m.card->description)},
         {"card_id", fmt::format("0x{:04X}", m.card->card_id)},
         {"module_ident", fmt::format("0x{:08X}", m.card->module_ident)}};
  json inputs = json::array();
  for (size_t i = 0; i < d.inputs().size(); ++i) {
    const InputChannel& in = d.inputs()[i];
    json c{{"channel", i},
           {"value", finite_or_zero(in.value)},
           {"unit", d.input_unit()},
           {"code", in.code},
           {"source", d.source(i).describe()}};
    if (d.has_sensor_break()) c["open"] = in.open;
    if (d.card().thermocouple_ohms) c["loop_ohms"] = in.loop_ohms;
    inputs.push_back(std::move(c));
  }
  json outputs = json::array();
  for (size_t i = 0; i < d.outputs().size(); ++i) {
    const OutputChannel& o = d.outputs()[i];
    json c{{"channel", i},   {"commanded", o.commanded}, {"driven", o.driven},
           {"wire", o.wire}, {"code", o.code},           {"unit", d.output_unit()}};
    if (d.detects_wiring_faults()) c["wiring_fault"] = fault_name(o.fault);
    outputs.push_back(std::move(c));
  }
  j["inputs"] = std::move(inputs);
  j["outputs"] = std::move(outputs);
  if (const auto* u = dynamic_cast<const UartDriver*>(&d)) {
    json ch = json::array();
    for (size_t c = 0; c < 4; ++c) {
      const UartDriver::Channel& uc = u->channel(c);
      ch.push_back({{"channel", c},
                    {"pty", uc.path},
                    {"baud", uc.config.baud_rate()},
                    {"parity", uc.config.parity == 0   ? "none"
                               : uc.config.parity == 1 ? "even"
                                                       : "odd"},
                    {"data_bits", 5 + std::min<int>(uc.config.data_bits, 3)},
                    {"stop_bits", uc.config.stop_bits ? 2 : 1},
                    {"flow", uc.config.flow == 0   ? "none"
                             : uc.config.flow == 1 ? "xon/xoff"
                                                   : "rts/cts"},
                    {"status", fmt::format("0x{:04X}", u->status_word(c))},
                    {"rx_available", uc.rx.size()},
                    {"tx_pending", uc.tx.size()},
                    {"errors", fmt::format("0x{:02X}", uc.errors.load())},
                    {"cts", uc.cts.load()},
                    {"hold", uc.hold.load()}});
    }
    j["uart"] = std::move(ch);
  }
  (void)rack;
  return j;
}

// The 0x10F3 diagnosis history (ETG.1020 ch. 13), oldest message first, with its text.
json diagnosis_json(Rack& rack) {
  const coe::diag::History& h = rack.device().diagnosis();
  json messages = json::array();
  for (size_t age = 0; age < h.count(); ++age) {
    const uint8_t sub = h.subindex_of(age);
    const auto m = coe::diag::decode(h.slot(sub));
    if (!m) continue;
    const auto rim = static_cast<uint8_t>(m->parameter(0));
    const auto module = static_cast<uint16_t>(m->parameter(1));
    const auto channel = static_cast<uint8_t>(m->parameter(2));
    const auto detail = static_cast<uint16_t>(m->parameter(3));
    const mdp::diag::DiagText* t = mdp::diag::find(m->text_id);
    json j{{"subindex", sub},
           {"diag_code", fmt::format("0x{:08X}", m->diag_code)},
           {"type", m->type == coe::diag::Type::Error     ? "error"
                    : m->type == coe::diag::Type::Warning ? "warning"
                                                          : "info"},
           {"text_id", fmt::format("0x{:04X}", m->text_id)},
           {"time_ns", m->time_ns},
           {"time_base", m->local_time ? "local" : "dc"},
           {"rim", rim},
           {"module", module},
           {"channel", channel == 0xFF ? json(nullptr) : json(channel)},
           {"detail", detail},
           {"acknowledged", age < h.acknowledged()},
           {"text", t ? mdp::diag::format(*t, rim, module, channel, detail)
                      : fmt::format("text 0x{:04X}", m->text_id)}};
    messages.push_back(std::move(j));
  }
  return {{"maximum_messages", h.capacity()},
          {"newest_message", h.newest_subindex()},
          {"newest_acknowledged", h.acknowledged() ? h.subindex_of(h.acknowledged() - 1) : 0},
          {"new_messages_available", h.new_messages()},
          {"flags", fmt::format("0x{:04X}", h.flags())},
          {"mode", h.acknowledge_mode() ? "acknowledge" : "overwrite"},
          {"messages", std::move(messages)}};
}

json exceptions_json(Rack& rack) {
  const ExceptionTree& t = rack.exceptions();
  auto hex32 = [](uint32_t v) { return fmt::format("0x{:08X}", v); };
  json rims = json::array();
  for (const auto& [rr, rim] : rack.rims()) {
    rims.push_back({{"rim", rr},
                    {"state", rim_state_name(rim.state)},
                    {"event_status", hex32(t.rim_event_status(rr))}});
  }
  json modules = json::array();
  for (const auto& d : rack.drivers()) {
    const uint16_t n = d->module().number;
    const uint32_t w = t.module_warnings(n, false), e = t.module_errors(n, false);
    const uint32_t wl = t.module_warnings(n, true), el = t.module_errors(n, true);
    if (w | e | wl | el) {
      modules.push_back({{"module", n},
                         {"F382", hex32(w)},
                         {"F384", hex32(e)},
                         {"F392", hex32(wl)},
                         {"F394", hex32(el)}});
    }
  }
  return {{"F380", hex32(t.summary(false))},
          {"F390", hex32(t.summary(true))},
          {"F386", hex32(t.global_warnings(false))},
          {"F388", hex32(t.global_errors(false))},
          {"F396", hex32(t.global_warnings(true))},
          {"F398", hex32(t.global_errors(true))},
          {"device_event_status", hex32(t.device_event_status())},
          {"rims", std::move(rims)},
          {"modules", std::move(modules)}};
}

// Every fan's speed: the control module's CPU fan and each RIM's two zones.
json fans_json(Rack& rack) {
  json rims = json::array();
  for (const auto& [rr, rim] : rack.rims()) {
    rims.push_back({{"rim", rr},
                    {"power_supply_fan", rim.power_supply_fan},
                    {"power_supply_rpm", rim.power_supply_rpm},
                    {"slot_card_fan", rim.slot_card_fan},
                    {"slot_card_rpm", rim.slot_card_rpm}});
  }
  return {{"cpu_fan_rpm", rack.cpu_fan_rpm()}, {"rims", std::move(rims)}};
}

json rack_json(Rack& rack) {
  json rims = json::array();
  for (const auto& [rr, rim] : rack.rims()) {
    rims.push_back({{"rim", rr},
                    {"state", rim_state_name(rim.state)},
                    {"comm_error", rim.comm_error},
                    {"power_supply_fan", rim.power_supply_fan},
                    {"power_supply_rpm", rim.power_supply_rpm},
                    {"slot_card_fan", rim.slot_card_fan},
                    {"slot_card_rpm", rim.slot_card_rpm},
                    {"modules", rim.modules}});
  }
  json modules = json::array();
  for (const auto& d : rack.drivers()) modules.push_back(module_json(rack, *d));
  return {{"esm", esm_state_name(rack.esm_state())},
          {"outputs_valid", rack.outputs_valid()},
          {"detect_modules_override", rack.detect_modules_override()},
          {"cpu_fan_rpm", rack.cpu_fan_rpm()},
          {"cpu_temperature", rack.cpu_temperature()},
          {"cpu_temperature_published", rack.cpu_temperature_published()},
          {"rims", std::move(rims)},
          {"modules", std::move(modules)}};
}

std::string param_string(const json& v) {
  if (v.is_string()) return v.get<std::string>();
  if (v.is_boolean()) return v.get<bool>() ? "true" : "false";
  if (v.is_number_integer()) return std::to_string(v.get<int64_t>());
  if (v.is_number()) return fmt::format("{}", v.get<double>());
  throw BadRequest("source parameters must be strings, numbers or booleans");
}

std::vector<uint8_t> parse_hex(const std::string& s) {
  std::vector<uint8_t> out;
  int nibble = -1;
  for (char c : s) {
    int v;
    if (c >= '0' && c <= '9')
      v = c - '0';
    else if (c >= 'a' && c <= 'f')
      v = c - 'a' + 10;
    else if (c >= 'A' && c <= 'F')
      v = c - 'A' + 10;
    else if (c == ' ' || c == ':')
      continue;
    else
      throw BadRequest(fmt::format("'hex' has a non-hex character '{}'", c));
    if (nibble < 0) {
      nibble = v;
    } else {
      out.push_back(static_cast<uint8_t>(nibble << 4 | v));
      nibble = -1;
    }
  }
  if (nibble >= 0) throw BadRequest("'hex' has an odd number of digits");
  return out;
}

}  // namespace

ControlApi::ControlApi(Rack& rack, PostFn post)
    : ControlApi(std::vector<Rack*>{&rack}, std::move(post), ControlApiOptions{}) {}

namespace {
std::vector<ControlSlave> rack_slaves(const std::vector<Rack*>& racks) {
  std::vector<ControlSlave> out;
  out.reserve(racks.size());
  for (Rack* r : racks) out.push_back({r, nullptr});
  return out;
}
}  // namespace

ControlApi::ControlApi(const std::vector<Rack*>& racks, PostFn post, ControlApiOptions options)
    : ControlApi(rack_slaves(racks), std::move(post), std::move(options)) {}

ControlApi::ControlApi(std::vector<ControlSlave> slaves, PostFn post, ControlApiOptions options)
    : slaves_(std::move(slaves)),
      post_(std::move(post)),
      options_(std::move(options)),
      alive_(std::make_shared<std::atomic<bool>>(true)),
      session_(options_.token, options_.token.empty() ? std::string() : new_token()) {
  racks_.reserve(slaves_.size());
  for (const ControlSlave& s : slaves_) racks_.push_back(s.rack);
}

ControlApi::~ControlApi() {
  stop();
}

std::string ControlApi::new_token() {
  uint8_t bytes[16];
  size_t got = 0;
  while (got < sizeof bytes) {
    const ssize_t n = ::getrandom(bytes + got, sizeof bytes - got, 0);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) throw std::runtime_error("getrandom failed");
    got += static_cast<size_t>(n);
  }
  std::string hex;
  for (uint8_t b : bytes) hex += fmt::format("{:02x}", b);
  return hex;
}

// --- the HTTP side -----------------------------------------------------------------------

namespace {

HttpResponse json_response(int status, const json& body) {
  HttpResponse r;
  r.status = status;
  r.body = body.dump(2) + "\n";
  return r;
}

HttpResponse refuse(int status, const std::string& reason) {
  return json_response(status, {{"error", reason}});
}

}  // namespace

std::optional<HttpResponse> ControlApi::check_head(const HttpRequest& req) const {
  const std::string port = std::to_string(port_);
  // DNS rebinding: a page of attacker.example that resolves to 127.0.0.1 still sends its own
  // name in Host (RFC 9110 §7.2).
  const auto host = req.header("host");
  if (!host || (*host != "127.0.0.1:" + port && *host != "localhost:" + port)) {
    return refuse(403, "Host must be 127.0.0.1:" + port + " or localhost:" + port);
  }
  // A browser names the page's origin on every cross-origin request (RFC 6454 §7).
  if (const auto origin = req.header("origin")) {
    if (*origin != "http://127.0.0.1:" + port && *origin != "http://localhost:" + port) {
      return refuse(403, "cross-origin requests are not accepted");
    }
  }
  // The login URL carries the per-run secret itself; WebSession::login checks it.
  if (req.path == kLoginPath && req.method == "GET") return std::nullopt;
  // The per-run secret (ctl, scripts) or the page's session cookie.
  const auto auth = req.header("authorization");
  constexpr std::string_view kBearer = "Bearer ";
  const bool bearer = auth && auth->substr(0, kBearer.size()) == kBearer &&
                      same_secret(auth->substr(kBearer.size()), options_.token);
  if (!bearer && !session_.has_session(req)) {
    HttpResponse r = refuse(401, "missing or wrong token (Authorization: Bearer, see " +
                                     std::string(kTokenFileName) +
                                     " in the state directory; a browser opens the login URL "
                                     "rackcat run printed)");
    r.headers.emplace_back("WWW-Authenticate", "Bearer");
    return r;
  }
  // A browser's state-changing request names its origin (Fetch §3.1 "Origin header"); one
  // that does not is not the page's own.
  if (!bearer && req.method == "POST" && !req.header("origin")) {
    return refuse(403, "a POST with the session cookie must carry the page's Origin");
  }
  if (req.method != "GET" && req.method != "POST") {
    HttpResponse r = refuse(405, "only GET and POST are accepted");
    r.headers.emplace_back("Allow", "GET, POST");
    return r;
  }
  if (req.method == "POST") {
    const auto type = req.header("content-type");
    const std::string_view t = type ? type->substr(0, type->find(';')) : std::string_view();
    if (t != "application/json") return refuse(415, "the body must be application/json");
  }
  return std::nullopt;
}

HttpResponse ControlApi::serve(const HttpRequest& req) {
  if (auto refused = check_head(req)) return *refused;
  if (req.path == kLoginPath) return session_.login(req);
  if (!req.path.starts_with("/api/")) return serve_page(req);
  if (req.path == "/api/stream") {
    if (req.method != "GET") {
      HttpResponse r = refuse(405, "/api/stream does not accept POST; use GET");
      r.headers.emplace_back("Allow", "GET");
      return r;
    }
    return open_stream();
  }
  const Response r = handle(req.method, req.path, req.body);
  HttpResponse out = json_response(r.status, r.body);
  if (!r.allow.empty()) out.headers.emplace_back("Allow", r.allow);
  return out;
}

HttpResponse ControlApi::serve_page(const HttpRequest& req) const {
  if (req.method != "GET") return refuse(405, "the page's files accept GET only");
  const WebAsset* asset = find_web_asset(req.path);
  if (asset == nullptr) return refuse(404, "no file " + printable(req.path));
  HttpResponse r;
  r.content_type = std::string(asset->content_type);
  r.body = std::string(asset->body);
  // The page loads only its own files and talks only to this API; no other site may frame
  // it (its buttons inject faults).
  r.headers.emplace_back("Content-Security-Policy",
                         "default-src 'none'; script-src 'self'; style-src 'self'; "
                         "img-src 'self' data:; connect-src 'self'; frame-ancestors 'none'; "
                         "base-uri 'none'; form-action 'none'");
  r.headers.emplace_back("X-Frame-Options", "DENY");
  r.headers.emplace_back("Referrer-Policy", "no-referrer");
  return r;
}

HttpResponse ControlApi::open_stream() {
  if (streams_->fetch_add(1) >= kMaxStreams) {
    streams_->fetch_sub(1);
    return refuse(503, "too many open streams");
  }
  // The count drops when the worker lets go of the response (the stream ended).
  auto slot =
      std::shared_ptr<void>(nullptr, [streams = streams_](void*) { streams->fetch_sub(1); });
  auto snapshot = std::make_shared<LiveSnapshot>(racks_);
  HttpResponse r;
  r.content_type = "text/event-stream";
  r.event_period = options_.stream_period;
  r.next_event = [this, snapshot, slot](std::string& out) {
    if (!alive_->load()) return false;
    const Response taken = execute([this, snapshot] {
      // Device thread: copies numbers into the snapshot's buffers, nothing else.
      snapshot->capture(racks_, options_.link);
      return Response{};
    });
    if (taken.status != 200) {
      out = ": busy\n\n";  // an SSE comment keeps the connection alive (HTML §9.2.6)
      return true;
    }
    out = "data: " + snapshot->to_json() + "\n\n";
    return true;
  };
  return r;
}

uint16_t ControlApi::listen(uint16_t port) {
  if (options_.token.size() < 32) {
    throw std::runtime_error("control API: no token (128 bits or more) to authenticate with");
  }
  server_ = std::make_unique<HttpServer>(
      options_.limits, [this](const HttpRequest& r) { return check_head(r); },
      [this](const HttpRequest& r) { return serve(r); });
  try {
    port_ = port;  // the head check needs it from the first request on
    port_ = server_->listen(port);
  } catch (const std::runtime_error& e) {
    server_.reset();
    throw std::runtime_error(std::string("control API: ") + e.what());
  }
  return port_;
}

void ControlApi::stop() {
  alive_->store(false);
  if (server_) server_->stop();
  server_.reset();
}

// --- requests ------------------------------------------------------------------------------

ControlApi::Response ControlApi::handle(std::string_view method, std::string_view path,
                                        std::string_view body) {
  Prepared p;
  try {
    p = prepare(method, path, body);
  } catch (const std::invalid_argument& e) {
    return {400, {{"error", printable(e.what())}}};
  } catch (const std::exception& e) {
    return {500, {{"error", printable(e.what())}}};
  }
  if (p.answer) return *p.answer;
  return execute(std::move(p.command));
}

ControlApi::Response ControlApi::execute(Command command) {
  auto guarded = [command = std::move(command)]() -> Response {
    try {
      return command();
    } catch (const std::invalid_argument& e) {
      return {400, {{"error", printable(e.what())}}};
    } catch (const std::exception& e) {
      return {500, {{"error", printable(e.what())}}};
    }
  };
  if (!post_) return guarded();
  // Bounded: a client cannot queue unlimited work for the device thread.
  if (in_flight_.fetch_add(1) >= kMaxInFlight) {
    in_flight_.fetch_sub(1);
    return {503, {{"error", "too many requests waiting for the device thread; nothing changed"}}};
  }
  enum class Stage { Queued, Taken, Done, Withdrawn };
  // Same clang-tidy 14 false positive as Response (llvm-project#54956): nlohmann::json's
  // noexcept members are looked into.
  // NOLINTNEXTLINE(bugprone-exception-escape)
  struct Ticket {
    std::mutex m;
    std::condition_variable cv;
    Stage stage = Stage::Queued;
    Response result;
  };
  auto ticket = std::make_shared<Ticket>();
  auto alive = alive_;
  post_([ticket, alive, guarded, this] {
    {
      std::lock_guard lock(ticket->m);
      if (ticket->stage == Stage::Withdrawn || !alive->load()) {
        ticket->stage = Stage::Withdrawn;
        in_flight_.fetch_sub(1);
        return;
      }
      ticket->stage = Stage::Taken;
    }
    Response r = guarded();
    {
      std::lock_guard lock(ticket->m);
      ticket->result = std::move(r);
      ticket->stage = Stage::Done;
    }
    in_flight_.fetch_sub(1);
    ticket->cv.notify_all();
  });
  std::unique_lock lock(ticket->m);
  if (!ticket->cv.wait_for(lock, options_.answer_timeout,
                           [&] { return ticket->stage == Stage::Done; })) {
    if (ticket->stage == Stage::Queued) {
      ticket->stage = Stage::Withdrawn;  // the device thread will skip it
      return {503,
              {{"error",
                "the device thread did not take the request in time; it was withdrawn "
                "and nothing changed"}}};
    }
    // Taken: it is being applied now; its real result follows within a cycle.
    ticket->cv.wait(lock, [&] { return ticket->stage == Stage::Done; });
  }
  return ticket->result;
}

ControlApi::Prepared ControlApi::prepare(std::string_view method, std::string_view path,
                                         std::string_view body) {
  // /api/slaves/N/... -> slave N; /api/... -> slave 0.
  size_t slave = 0;
  std::string rest(path);
  constexpr std::string_view kSlaves = "/api/slaves";
  if (path == kSlaves) {
    if (method != "GET") {
      return {Response{405, {{"error", "/api/slaves does not accept " + printable(method)}}, "GET"},
              {}};
    }
    json list = json::array();
    for (size_t i = 0; i < slaves_.size(); ++i) {
      if (slaves_[i].rack) {
        list.push_back({{"slave", i}, {"modules", slaves_[i].rack->drivers().size()}});
      } else {
        list.push_back({{"slave", i}, {"device", slaves_[i].io->describe()}});
      }
    }
    return {Response{200, {{"slaves", std::move(list)}}}, {}};
  }
  if (path.starts_with("/api/slaves/")) {
    std::string_view tail = path.substr(kSlaves.size() + 1);
    const size_t slash = tail.find('/');
    const std::string_view num = tail.substr(0, slash);
    size_t n = 0;
    bool ok = !num.empty() && num.size() <= 3;
    for (char c : num) {
      ok = ok && c >= '0' && c <= '9';
      n = n * 10 + static_cast<size_t>(c - '0');
    }
    if (!ok || n >= slaves_.size()) {
      return {Response{404,
                       {{"error", fmt::format("there is no slave {} (the segment has {})",
                                              printable(num), slaves_.size())}}},
              {}};
    }
    slave = n;
    rest = "/api" + std::string(slash == std::string_view::npos ? "" : tail.substr(slash));
  }
  json parsed = json::object();
  if (!body.empty()) {
    parsed = json::parse(body, nullptr, false);
    if (parsed.is_discarded()) {
      return {Response{400, {{"error", "the request body is not valid JSON"}}}, {}};
    }
  }
  if (slaves_[slave].io) return dispatch_io(slave, *slaves_[slave].io, method, rest, parsed);
  return dispatch(*slaves_[slave].rack, method, rest, parsed);
}

namespace {
std::string to_hex(const std::vector<uint8_t>& bytes) {
  std::string out;
  out.reserve(bytes.size() * 2);
  for (uint8_t b : bytes) out += fmt::format("{:02X}", b);
  return out;
}

json io_json(size_t slave, const IoDevice& io) {
  const auto out = io.outputs();
  const auto in = io.inputs();
  return {{"slave", slave},         {"device", io.describe()},
          {"outputs", to_hex(out)}, {"output_bits", out.size() * 8},
          {"inputs", to_hex(in)},   {"input_bits", in.size() * 8}};
}
}  // namespace

ControlApi::Prepared ControlApi::dispatch_io(size_t slave, IoDevice& io, std::string_view method,
                                             std::string_view path, const json& body) {
  auto answer = [](Response resp) { return Prepared{std::move(resp), {}}; };
  auto bad = [&](const std::string& why) { return answer(Response{400, {{"error", why}}}); };
  if (path == "/api/io") {
    if (method != "GET") {
      return answer(Response{
          405, {{"error", "/api/io does not accept " + printable(method) + "; use GET"}}, "GET"});
    }
    return {std::nullopt, [slave, &io] { return Response{200, io_json(slave, io)}; }};
  }
  if (path == "/api/io/inputs") {
    if (method != "POST") {
      return answer(Response{
          405,
          {{"error", "/api/io/inputs does not accept " + printable(method) + "; use POST"}},
          "POST"});
    }
    // {"data": "HEX", "bit": B (default 0), "bits": N (default 8 * bytes of data)}
    known_fields(body, path, {"data", "bit", "bits"});
    if (!body.is_object() || !body.contains("data") || !body["data"].is_string()) {
      return bad("POST /api/io/inputs needs {\"data\": \"HEX\"} (and optionally bit, bits)");
    }
    const std::string hex = body["data"].get<std::string>();
    if (hex.empty() || hex.size() % 2 != 0 || hex.size() > 2 * 1024 ||
        hex.find_first_not_of("0123456789abcdefABCDEF") != std::string::npos) {
      return bad("data: \"" + printable(hex) + "\" is not 1..1024 bytes of hex");
    }
    std::vector<uint8_t> data(hex.size() / 2);
    for (size_t i = 0; i < data.size(); ++i) {
      data[i] = static_cast<uint8_t>(std::stoul(hex.substr(2 * i, 2), nullptr, 16));
    }
    auto count = [&](const char* key, size_t dflt) -> std::optional<size_t> {
      if (!body.contains(key)) return dflt;
      if (!body[key].is_number_integer() || body[key].get<int64_t>() < 0) return std::nullopt;
      return body[key].get<size_t>();
    };
    const auto bit = count("bit", 0);
    const auto bits = count("bits", data.size() * 8);
    if (!bit || !bits || *bits == 0 || *bits > data.size() * 8) {
      return bad("bit and bits are unsigned numbers, bits 1.." + std::to_string(data.size() * 8) +
                 " (the bits of data)");
    }
    const size_t have = io.inputs().size() * 8;
    if (*bit > have || *bits > have - *bit) {
      return bad(fmt::format("input bits {}..{} are beyond the {} input bit(s) of slave {} ({})",
                             *bit, *bit + *bits - 1, have, slave, io.describe()));
    }
    return {std::nullopt, [slave, &io, data, b = *bit, n = *bits] {
              io.set_input_bits(b, n, data);
              return Response{200, io_json(slave, io)};
            }};
  }
  return answer(
      Response{404,
               {{"error", fmt::format("slave {} is {} from its ESI: it has GET /api/io and POST "
                                      "/api/io/inputs, not {}",
                                      slave, io.describe(), printable(path))}}});
}

ControlApi::Prepared ControlApi::dispatch(Rack& rack, std::string_view method,
                                          std::string_view path, const json& body) {
  const bool get = method == "GET";
  const bool post = method == "POST";
  Rack* r = &rack;
  auto answer = [](Response resp) { return Prepared{std::move(resp), {}}; };
  auto run = [](Command c) { return Prepared{std::nullopt, std::move(c)}; };
  // Every endpoint takes exactly one of GET and POST: the other one is named in the answer.
  auto wrong_method = [&](const char* accepted) {
    return answer(Response{405,
                           {{"error", fmt::format("{} does not accept {}; use {}", printable(path),
                                                  printable(method), accepted)}},
                           accepted});
  };

  if (path == "/api/rack") {
    if (!get) return wrong_method("GET");
    return run([r] {
      r->refresh();
      return Response{200, rack_json(*r)};
    });
  }
  if (path.starts_with("/api/modules/")) {
    if (!get) return wrong_method("GET");
    const std::string_view num = path.substr(std::string_view("/api/modules/").size());
    int n = 0;
    for (char c : num) {
      if (c < '0' || c > '9' || n > 1000) throw BadRequest("module number must be 1..255");
      n = n * 10 + (c - '0');
    }
    CardDriver* d = rack.driver(static_cast<uint16_t>(n));
    if (num.empty() || d == nullptr)
      return answer({404, {{"error", fmt::format("there is no module {}", printable(num))}}});
    return run([r, d] {
      r->refresh();
      return Response{200, module_json(*r, *d)};
    });
  }
  if (path == "/api/esm") {
    if (!get) return wrong_method("GET");
    return run([r] {
      return Response{200,
                      {{"state", esm_state_name(r->esm_state())},
                       {"outputs_valid", r->outputs_valid()},
                       {"detect_modules_override", r->detect_modules_override()}}};
    });
  }
  if (path == "/api/exceptions") {
    if (!get) return wrong_method("GET");
    return run([r] {
      r->refresh();
      return Response{200, exceptions_json(*r)};
    });
  }
  if (path == "/api/exceptions/clear") {
    if (!post) return wrong_method("POST");
    known_fields(body, path, {});
    return run([r] {
      r->device().reset_exceptions();  // as the master's 0xFBF1
      r->refresh();
      return Response{200, exceptions_json(*r)};
    });
  }
  if (path == "/api/channel") {
    if (!post) return wrong_method("POST");
    known_fields(body, path, {"module", "channel", "value", "source", "params"});
    const auto module = static_cast<uint16_t>(integer(body, "module", 1, 255));
    const auto channel = static_cast<size_t>(integer(body, "channel", 0, 31));
    std::string kind;
    SourceParams params;
    if (body.contains("value")) {
      kind = "constant";
      params["value"] = param_string(field(body, "value"));
      if (body.contains("source")) throw BadRequest("give either 'value' or 'source', not both");
    } else {
      if (!body.contains("source")) throw BadRequest("give 'value' or 'source' (with 'params')");
      kind = text(body, "source");
      if (body.contains("params")) {
        const json& p = body.at("params");
        if (!p.is_object()) throw BadRequest("'params' must be an object");
        for (auto it = p.begin(); it != p.end(); ++it) params[it.key()] = param_string(it.value());
      }
    }
    if (rack.driver(module) == nullptr)
      throw BadRequest(fmt::format("there is no module {}", module));
    // A recording is read and parsed here, below --data-dir, never on the device thread.
    auto prebuilt = std::make_shared<std::unique_ptr<Source>>();
    if (kind == "replay") {
      SourceContext ctx;
      auto data = options_.data;
      ctx.read_file = [data](const std::string& file, size_t max_bytes) -> std::string {
        if (!data) {
          throw std::invalid_argument("replay files are read below --data-dir, and none was given");
        }
        return data->read(file, max_bytes);
      };
      SourceParams own;
      for (const auto& [k, v] : params) {
        if (!is_channel_option_key(k)) own[k] = v;
      }
      *prebuilt = make_source(kind, own, ctx);
    }
    return run([r, module, channel, kind, params, prebuilt] {
      r->set_source(module, channel, kind, params, std::move(*prebuilt));
      r->sample_inputs(module);  // the answer shows the new value, not the last cycle's
      r->refresh();
      return Response{200, module_json(*r, *r->driver(module))};
    });
  }
  if (path == "/api/rim/unplug" || path == "/api/rim/replug" || path == "/api/rim/state") {
    if (!post) return wrong_method("POST");
    if (path == "/api/rim/unplug") known_fields(body, path, {"rim", "comm_error"});
    if (path == "/api/rim/replug") known_fields(body, path, {"rim"});
    if (path == "/api/rim/state") known_fields(body, path, {"rim", "state", "comm_error"});
    const auto rr = static_cast<uint8_t>(integer(body, "rim", 1, 5));
    if (!rack.rims().count(rr)) throw BadRequest(fmt::format("there is no RIM {}", rr));
    RimState st = RimState::Online;
    const bool comm_error = boolean(body, "comm_error", false);
    if (path == "/api/rim/unplug") {
      st = RimState::Offline;
    } else if (path == "/api/rim/state") {
      const std::optional<RimState> named = rim_state_from_name(text(body, "state"));
      if (!named) throw BadRequest("'state' must be offline, connected, online or error");
      st = *named;
    }
    const bool err = path == "/api/rim/replug" ? false : comm_error;
    return run([r, rr, st, err] {
      r->set_rim_state(rr, st, err);
      r->refresh();
      return Response{200, exceptions_json(*r)};
    });
  }
  if (path == "/api/rim/mcm") {
    if (!post) return wrong_method("POST");
    known_fields(body, path, {"rim", "errors"});
    const auto rr = static_cast<uint8_t>(integer(body, "rim", 1, 5));
    if (!rack.rims().count(rr)) throw BadRequest(fmt::format("there is no RIM {}", rr));
    const json& list = field(body, "errors");
    if (!list.is_array()) throw BadRequest("'errors' must be an array (possibly empty)");
    uint32_t bits = 0;
    for (const json& e : list) {
      const std::string name = e.is_string() ? e.get<std::string>() : std::string();
      if (name == "slot_machine_mcm0")
        bits |= rim_event::kSlotMachineMcm0;
      else if (name == "sout_compare_mcm0")
        bits |= rim_event::kSoutCompareMcm0;
      else if (name == "slot_machine_mcm1")
        bits |= rim_event::kSlotMachineMcm1;
      else if (name == "sout_compare_mcm1")
        bits |= rim_event::kSoutCompareMcm1;
      else
        throw BadRequest(
            fmt::format("'errors' entry {} is not one of slot_machine_mcm0, sout_compare_mcm0, "
                        "slot_machine_mcm1, sout_compare_mcm1",
                        printable(e.dump())));
    }
    return run([r, rr, bits] {
      r->set_rim_mcm_errors(rr, bits);
      r->refresh();
      return Response{200, exceptions_json(*r)};
    });
  }
  if (path == "/api/fan") {
    if (!post) return wrong_method("POST");
    known_fields(body, path, {"rim", "zone", "rpm"});
    const auto rr = static_cast<uint8_t>(integer(body, "rim", 0, 5));
    const std::string zone = body.contains("zone") ? text(body, "zone") : std::string();
    const double rpm = number(body, "rpm");
    return run([r, rr, zone, rpm] {
      r->set_fan_rpm(rr, zone, rpm);
      r->refresh();
      // The fans as they are now, and the tree their speed feeds (guide §4.8 fan warnings).
      json j = exceptions_json(*r);
      j["fans"] = fans_json(*r);
      return Response{200, j};
    });
  }
  if (path == "/api/cpu_temperature") {
    if (!post) return wrong_method("POST");
    known_fields(body, path, {"celsius", "immediate"});
    const double celsius = number(body, "celsius");
    const bool immediate = boolean(body, "immediate", false);
    return run([r, celsius, immediate] {
      r->set_cpu_temperature(celsius, immediate);
      return Response{200,
                      {{"cpu_temperature", r->cpu_temperature()},
                       {"published", r->cpu_temperature_published()}}};
    });
  }
  if (path == "/api/diagnosis") {
    if (!get) return wrong_method("GET");
    return run([r] {
      r->refresh();
      return Response{200, diagnosis_json(*r)};
    });
  }
  if (path == "/api/output_fault") {
    if (!post) return wrong_method("POST");
    known_fields(body, path, {"module", "channel", "overload", "overtemperature"});
    const auto module = static_cast<uint16_t>(integer(body, "module", 1, 255));
    const auto channel = static_cast<size_t>(integer(body, "channel", 0, 31));
    if (!body.contains("overload") && !body.contains("overtemperature"))
      throw BadRequest("give 'overload' and/or 'overtemperature'");
    std::optional<bool> overload, overtemp;
    if (body.contains("overload")) overload = boolean(body, "overload", false);
    if (body.contains("overtemperature")) overtemp = boolean(body, "overtemperature", false);
    return run([r, module, channel, overload, overtemp] {
      CardDriver* d = r->driver(module);
      const bool known = d != nullptr && channel < d->outputs().size();
      r->set_output_fault(module, channel,
                          overload.value_or(known && d->outputs()[channel].overload),
                          overtemp.value_or(known && d->outputs()[channel].overtemperature));
      r->refresh();
      return Response{200, diagnosis_json(*r)};
    });
  }
  if (path == "/api/encoder_fault") {
    // {module, fault: hardware|jump|frozen, active?: bool (default true), steps?: jump size}
    if (!post) return wrong_method("POST");
    known_fields(body, path, {"module", "fault", "active", "steps"});
    const auto module = static_cast<uint16_t>(integer(body, "module", 1, 255));
    const std::string f = text(body, "fault");
    EncoderFault fault;
    if (f == "hardware")
      fault = EncoderFault::Hardware;
    else if (f == "jump")
      fault = EncoderFault::Jump;
    else if (f == "frozen")
      fault = EncoderFault::Frozen;
    else
      throw BadRequest("'fault' must be hardware, jump or frozen");
    const bool active = body.contains("active") ? boolean(body, "active", true) : true;
    const int64_t steps = body.contains("steps")
                              ? integer(body, "steps", -(int64_t{1} << 40), int64_t{1} << 40)
                              : 1000;
    return run([r, module, fault, active, steps] {
      r->set_encoder_fault(module, fault, active, steps);
      r->refresh();
      return Response{200, diagnosis_json(*r)};
    });
  }
  if (path == "/api/wiring_fault") {
    if (!post) return wrong_method("POST");
    known_fields(body, path, {"module", "channel", "fault"});
    const auto module = static_cast<uint16_t>(integer(body, "module", 1, 255));
    const auto channel = static_cast<size_t>(integer(body, "channel", 0, 31));
    const std::string f = text(body, "fault");
    WiringFault fault;
    if (f == "none")
      fault = WiringFault::None;
    else if (f == "safe" || f == "short_to_ground")
      fault = WiringFault::ShortToGround;
    else if (f == "unsafe" || f == "short_to_supply")
      fault = WiringFault::ShortToSupply;
    else
      throw BadRequest("'fault' must be none, safe (short_to_ground) or unsafe (short_to_supply)");
    return run([r, module, channel, fault] {
      r->set_wiring_fault(module, channel, fault);
      r->refresh();
      // The channel's wire as it is now, and the tree the fault feeds (guide §4.7, §3.4).
      json j = exceptions_json(*r);
      j["module_state"] = module_json(*r, *r->driver(module));
      return Response{200, j};
    });
  }
  if (path == "/api/sensor") {
    if (!post) return wrong_method("POST");
    known_fields(body, path, {"module", "channel", "open", "loop_ohms"});
    const auto module = static_cast<uint16_t>(integer(body, "module", 1, 255));
    const auto channel = static_cast<size_t>(integer(body, "channel", 0, 31));
    if (!body.contains("open") && !body.contains("loop_ohms"))
      throw BadRequest("give 'open' and/or 'loop_ohms'");
    std::optional<double> ohms;
    std::optional<bool> open;
    if (body.contains("loop_ohms")) ohms = number(body, "loop_ohms");
    if (body.contains("open")) open = boolean(body, "open", false);
    return run([r, module, channel, ohms, open] {
      if (ohms) r->set_loop_ohms(module, channel, *ohms);
      if (open) r->set_sensor_open(module, channel, *open);
      r->refresh();
      return Response{200, module_json(*r, *r->driver(module))};
    });
  }
  if (path == "/api/uart/inject") {
    if (!post) return wrong_method("POST");
    known_fields(body, path, {"module", "channel", "text", "hex", "error", "cts"});
    const auto module = static_cast<uint16_t>(integer(body, "module", 1, 255));
    const auto channel = static_cast<size_t>(integer(body, "channel", 0, 3));
    auto* u = dynamic_cast<UartDriver*>(rack.driver(module));
    if (u == nullptr) throw BadRequest(fmt::format("module {} is not a UART card", module));
    std::vector<uint8_t> bytes;
    if (body.contains("text")) {
      const std::string t = text(body, "text");
      bytes.assign(t.begin(), t.end());
    }
    if (body.contains("hex")) {
      const auto h = parse_hex(text(body, "hex"));
      bytes.insert(bytes.end(), h.begin(), h.end());
    }
    uint8_t error_bits = 0;
    if (body.contains("error")) {
      const std::string e = text(body, "error");
      if (e == "overflow")
        error_bits = uart::kErrRxOverflow;
      else if (e == "framing")
        error_bits = uart::kErrFraming;
      else if (e == "parity")
        error_bits = uart::kErrParity;
      else if (e == "tx_overflow")
        error_bits = uart::kErrTxOverflow;
      else
        throw BadRequest("'error' must be overflow, framing, parity or tx_overflow");
    }
    const bool has_cts = body.contains("cts");
    const bool cts = boolean(body, "cts", true);
    if (bytes.empty() && error_bits == 0 && !has_cts)
      throw BadRequest("give 'text', 'hex', 'error' and/or 'cts'");
    return run([r, u, channel, bytes, error_bits, has_cts, cts] {
      const size_t accepted = u->inject_rx(channel, bytes.data(), bytes.size());
      if (error_bits) u->inject_error(channel, error_bits);
      if (has_cts) u->channel(channel).cts = cts;
      r->refresh();
      json j = module_json(*r, *u);
      j["accepted"] = accepted;
      return Response{200, j};
    });
  }
  return answer(
      {404, {{"error", fmt::format("no endpoint {} {}", printable(method), printable(path))}}});
}

}  // namespace rackcat::modules
