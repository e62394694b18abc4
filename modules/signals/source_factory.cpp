#include "modules/signals/source_factory.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <numbers>
#include <optional>
#include <set>
#include <stdexcept>

#include "modules/signals/state_space_plant.hpp"

namespace rackcat::modules {
namespace {

std::string_view trim(std::string_view s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
  return s;
}

bool to_double(std::string_view s, double& out) {
  s = trim(s);
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  if (s.empty()) return false;
  const auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), out);
  return ec == std::errc() && p == s.data() + s.size() && std::isfinite(out);
}

class Params {
 public:
  Params(std::string_view kind, const SourceParams& p) : kind_(kind), p_(p) {}

  double number(const char* key, std::optional<double> fallback = std::nullopt) {
    used_.insert(key);
    auto it = p_.find(key);
    if (it == p_.end()) {
      if (fallback) return *fallback;
      throw std::invalid_argument(fmt::format("{}: missing parameter '{}'", kind_, key));
    }
    double v = 0;
    if (!to_double(it->second, v))
      throw std::invalid_argument(
          fmt::format("{}: parameter '{}' is not a number: '{}'", kind_, key, it->second));
    return v;
  }
  bool has(const char* key) const { return p_.count(key) != 0; }
  std::string text(const char* key) {
    used_.insert(key);
    auto it = p_.find(key);
    if (it == p_.end())
      throw std::invalid_argument(fmt::format("{}: missing parameter '{}'", kind_, key));
    return it->second;
  }
  bool flag(const char* key, bool fallback) {
    used_.insert(key);
    auto it = p_.find(key);
    if (it == p_.end()) return fallback;
    if (it->second == "true" || it->second == "1" || it->second == "yes") return true;
    if (it->second == "false" || it->second == "0" || it->second == "no") return false;
    throw std::invalid_argument(
        fmt::format("{}: parameter '{}' must be true or false: '{}'", kind_, key, it->second));
  }
  void mark(std::initializer_list<const char*> keys) {
    for (const char* k : keys) used_.insert(k);
  }
  // Before anything is read: a misspelt parameter is named as such, not reported as a
  // missing one ("amplitud" -> unknown parameter, not "give 'frequency' or 'period_s'").
  void check_known(std::initializer_list<std::string_view> known) const {
    for (const auto& [k, v] : p_) {
      if (is_channel_option_key(k) || k == "source") continue;
      if (std::find(known.begin(), known.end(), k) == known.end()) {
        throw std::invalid_argument(fmt::format("{}: unknown parameter '{}' (known: {})", kind_, k,
                                                fmt::join(known, ", ")));
      }
    }
  }
  // Every parameter must be understood: a typo must not silently fall back to a default.
  void check_unused() const {
    for (const auto& [k, v] : p_) {
      if (!used_.count(k) && !is_channel_option_key(k) && k != "source")
        throw std::invalid_argument(fmt::format("{}: unknown parameter '{}'", kind_, k));
    }
  }

 private:
  std::string_view kind_;
  const SourceParams& p_;
  std::set<std::string, std::less<>> used_;
};

uint8_t small_int(Params& p, const char* key, double max) {
  const double v = p.number(key);
  if (v < 0 || v > max || v != std::floor(v))
    throw std::invalid_argument(fmt::format("parameter '{}' must be an integer 0..{}", key, max));
  return static_cast<uint8_t>(v);
}

}  // namespace

bool is_channel_option_key(std::string_view key) {
  return key == "loop_ohms" || key == "open" || key == "cold_junction_c";
}

MatrixText parse_matrix(std::string_view text, std::string_view what) {
  MatrixText m;
  size_t start = 0;
  while (start <= text.size()) {
    size_t end = text.find(';', start);
    if (end == std::string_view::npos) end = text.size();
    std::string_view row = trim(text.substr(start, end - start));
    size_t cols = 0;
    while (!row.empty()) {
      size_t sep = row.find_first_of(" \t,");
      std::string_view cell = row.substr(0, sep);
      double v = 0;
      if (!to_double(cell, v))
        throw std::invalid_argument(fmt::format("{}: '{}' is not a number", what, cell));
      m.values.push_back(v);
      ++cols;
      row = sep == std::string_view::npos ? std::string_view{} : trim(row.substr(sep + 1));
    }
    if (cols == 0) throw std::invalid_argument(fmt::format("{}: empty row", what));
    if (m.rows > 0 && cols != m.cols)
      throw std::invalid_argument(fmt::format("{}: rows have different lengths", what));
    m.cols = cols;
    ++m.rows;
    start = end + 1;
  }
  return m;
}

namespace {
Eigen::MatrixXd to_eigen(const MatrixText& t) {
  Eigen::MatrixXd m(static_cast<Eigen::Index>(t.rows), static_cast<Eigen::Index>(t.cols));
  for (size_t r = 0; r < t.rows; ++r)
    for (size_t c = 0; c < t.cols; ++c)
      m(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c)) = t.values[r * t.cols + c];
  return m;
}
}  // namespace

std::unique_ptr<StateSpacePlant> make_plant(
    const SourceParams& params, double dt,
    const std::function<OutputRef(const std::string&)>& input) {
  auto get = [&](const char* k) -> std::string {
    auto it = params.find(k);
    if (it == params.end())
      throw std::invalid_argument(fmt::format("plant: missing parameter '{}'", k));
    return it->second;
  };
  Eigen::MatrixXd a = to_eigen(parse_matrix(get("a"), "plant a"));
  Eigen::MatrixXd b = to_eigen(parse_matrix(get("b"), "plant b"));
  Eigen::MatrixXd c = to_eigen(parse_matrix(get("c"), "plant c"));
  Eigen::MatrixXd d;
  if (params.count("d")) d = to_eigen(parse_matrix(params.at("d"), "plant d"));
  // Small plants only: the matrix exponential is computed once, but every cycle pays n^2.
  constexpr Eigen::Index kMaxDim = 32;
  if (a.rows() > kMaxDim || b.cols() > kMaxDim || c.rows() > kMaxDim)
    throw std::invalid_argument("plant: at most 32 states, inputs and outputs");
  auto plant = std::make_unique<StateSpacePlant>(a, b, std::move(c), std::move(d), dt);
  if (params.count("x0")) {
    const MatrixText x0 = parse_matrix(params.at("x0"), "plant x0");
    if (x0.values.size() != plant->states())
      throw std::invalid_argument("plant: x0 needs one value per state");
    plant->set_state(Eigen::Map<const Eigen::VectorXd>(
        x0.values.data(), static_cast<Eigen::Index>(x0.values.size())));
  }
  if (params.count("inputs")) {
    std::string_view list = params.at("inputs");
    size_t k = 0;
    while (!list.empty()) {
      const size_t comma = list.find(',');
      const std::string item(trim(list.substr(0, comma)));
      list = comma == std::string_view::npos ? std::string_view{} : list.substr(comma + 1);
      if (item.empty()) continue;
      if (k >= plant->inputs()) throw std::invalid_argument("plant: more inputs than columns of b");
      const OutputRef ref = input(item);
      if (ref.value == nullptr) throw std::invalid_argument("plant: input " + ref.name);
      plant->bind_input(k++, ref.value);
    }
  }
  return plant;
}

std::unique_ptr<Source> make_source(std::string_view kind, const SourceParams& params,
                                    SourceContext& ctx) {
  Params p(kind, params);
  if (kind == "constant") {
    p.check_known({"value"});
  } else if (kind == "ramp") {
    p.check_known({"from", "to", "period_s"});
  } else if (kind == "sine") {
    p.check_known({"amplitude", "frequency", "period_s", "offset", "phase"});
  } else if (kind == "noise") {
    p.check_known({"mean", "stddev", "seed"});
  } else if (kind == "replay") {
    p.check_known({"file", "loop"});
  } else if (kind == "clock") {
    p.check_known({"tick_us"});
  } else if (kind == "loopback") {
    p.check_known({"module", "rim", "slot", "channel", "gain", "offset"});
  } else if (kind == "plant") {
    p.check_known({"plant", "a", "b", "c", "d", "x0", "inputs", "output"});
  }
  std::unique_ptr<Source> s;
  if (kind == "constant") {
    s = std::make_unique<ConstantSource>(p.number("value", 0.0));
  } else if (kind == "ramp") {
    s = std::make_unique<RampSource>(p.number("from"), p.number("to"), p.number("period_s"));
  } else if (kind == "sine") {
    double freq = 0;
    if (p.has("frequency")) {
      freq = p.number("frequency");
    } else {
      if (!p.has("period_s"))
        throw std::invalid_argument("sine: give 'frequency' (Hz) or 'period_s' (s)");
      const double period = p.number("period_s");
      if (!(period > 0)) throw std::invalid_argument("sine: period_s must be > 0");
      freq = 1.0 / period;
    }
    s = std::make_unique<SineSource>(p.number("amplitude"), freq, p.number("offset", 0.0),
                                     p.number("phase", 0.0));
  } else if (kind == "noise") {
    const double seed = p.number("seed", 1.0);
    if (seed < 0 || seed != std::floor(seed) || seed > 9.007199254740992e15)
      throw std::invalid_argument("noise: seed must be a non-negative integer");
    s = std::make_unique<NoiseSource>(p.number("mean", 0.0), p.number("stddev"),
                                      static_cast<uint64_t>(seed));
  } else if (kind == "replay") {
    const std::string file = p.text("file");
    const bool loop = p.flag("loop", true);
    try {
      s = ctx.read_file ? ReplaySource::from_text(
                              ctx.read_file(file, ReplaySource::kMaxReplayBytes), file, loop)
                        : ReplaySource::from_csv(file, loop);
    } catch (const std::runtime_error& e) {
      throw std::invalid_argument(std::string("replay: ") + e.what());  // a bad request
    }
  } else if (kind == "clock") {
    s = std::make_unique<ClockSource>(p.number("tick_us", 10.0));
  } else if (kind == "loopback") {
    uint8_t rim = 0, slot = 0;
    if (p.has("module")) {
      const double m = p.number("module");
      if (m < 1 || m > 255 || m != std::floor(m) || !ctx.module_position ||
          !ctx.module_position(static_cast<uint16_t>(m), rim, slot))
        throw std::invalid_argument(fmt::format("loopback: no module {}", params.at("module")));
    } else {
      rim = small_int(p, "rim", 5);
      slot = small_int(p, "slot", 24);
    }
    const uint8_t channel = small_int(p, "channel", 31);
    const OutputRef ref = ctx.output ? ctx.output(rim, slot, channel) : OutputRef{};
    if (ref.value == nullptr) throw std::invalid_argument("loopback: " + ref.name);
    s = std::make_unique<LoopbackSource>(ref.value, ref.name, p.number("gain", 1.0),
                                         p.number("offset", 0.0));
  } else if (kind == "plant") {
    const std::string name = p.text("plant");
    p.mark({"a", "b", "c", "d", "x0", "inputs"});
    if (!ctx.plant) throw std::invalid_argument("plant: no plants in this context");
    StateSpacePlant& plant = ctx.plant(name, params);
    const double out = p.number("output", 0.0);
    if (out < 0 || out != std::floor(out) || out >= static_cast<double>(plant.outputs()))
      throw std::invalid_argument(fmt::format("plant: output {} out of range (plant '{}' has {})",
                                              out, name, plant.outputs()));
    s = std::make_unique<PlantSource>(plant, static_cast<size_t>(out), name);
  } else {
    throw std::invalid_argument(fmt::format(
        "unknown source '{}' (constant, ramp, sine, noise, replay, loopback, plant, clock)", kind));
  }
  p.check_unused();
  return s;
}

}  // namespace rackcat::modules
