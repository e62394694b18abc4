#include "modules/signals/signal_source.hpp"

#include <fmt/format.h>

#include <charconv>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <stdexcept>
#include <string_view>

#include "modules/signals/state_space_plant.hpp"

namespace rackcat::modules {

std::string ConstantSource::describe() const {
  return fmt::format("constant value={}", value_);
}

RampSource::RampSource(double from, double to, double period_s)
    : from_(from), to_(to), period_(period_s) {
  if (!(period_s > 0.0)) throw std::invalid_argument("ramp: period must be > 0");
}

double RampSource::sample(double t) {
  const double phase = t / period_ - std::floor(t / period_);
  return from_ + (to_ - from_) * phase;
}

std::string RampSource::describe() const {
  return fmt::format("ramp from={} to={} period={}", from_, to_, period_);
}

SineSource::SineSource(double amplitude, double frequency_hz, double offset, double phase_rad)
    : amplitude_(amplitude), frequency_(frequency_hz), offset_(offset), phase_(phase_rad) {
  if (!(frequency_hz >= 0.0)) throw std::invalid_argument("sine: frequency must be >= 0");
}

double SineSource::sample(double t) {
  return offset_ + amplitude_ * std::sin(2.0 * std::numbers::pi * frequency_ * t + phase_);
}

std::string SineSource::describe() const {
  return fmt::format("sine amplitude={} frequency={} offset={} phase={}", amplitude_, frequency_,
                     offset_, phase_);
}

ClockSource::ClockSource(double tick_us) : tick_ns_(static_cast<int64_t>(tick_us * 1000.0)) {
  if (!(tick_us >= 1.0) || tick_us > 1e6) {
    throw std::invalid_argument("clock: tick_us must be 1..1000000");
  }
}

int16_t ClockSource::code_at(int64_t monotonic_ns) const {
  return static_cast<int16_t>((monotonic_ns / tick_ns_) % 65535 - 32767);
}

double ClockSource::sample(double) {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);  // vDSO: no system call, no allocation
  const int64_t ns = static_cast<int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
  return code_at(ns) * 10.0 / 32767.0;  // AnalogScale turns it back into the same code
}

std::string ClockSource::describe() const {
  return fmt::format("clock tick_us={}", static_cast<double>(tick_ns_) / 1000.0);
}

namespace {
uint64_t splitmix64(uint64_t& x) {
  uint64_t z = (x += 0x9E3779B97F4A7C15ULL);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}
uint64_t rotl(uint64_t x, int k) {
  return (x << k) | (x >> (64 - k));
}
}  // namespace

Prng::Prng(uint64_t seed) {
  for (auto& s : s_) s = splitmix64(seed);
}

uint64_t Prng::next() {
  const uint64_t result = rotl(s_[1] * 5, 7) * 9;
  const uint64_t t = s_[1] << 17;
  s_[2] ^= s_[0];
  s_[3] ^= s_[1];
  s_[1] ^= s_[2];
  s_[0] ^= s_[3];
  s_[2] ^= t;
  s_[3] = rotl(s_[3], 45);
  return result;
}

double Prng::uniform() {
  // 53 random bits -> [0, 1), shifted to (0, 1] so log() below is finite.
  return (static_cast<double>(next() >> 11) + 1.0) * 0x1.0p-53;
}

double Prng::gaussian() {
  if (has_spare_) {
    has_spare_ = false;
    return spare_;
  }
  const double r = std::sqrt(-2.0 * std::log(uniform()));
  const double theta = 2.0 * std::numbers::pi * uniform();
  spare_ = r * std::sin(theta);
  has_spare_ = true;
  return r * std::cos(theta);
}

NoiseSource::NoiseSource(double mean, double stddev, uint64_t seed)
    : mean_(mean), stddev_(stddev), seed_(seed), prng_(seed) {
  if (!(stddev >= 0.0)) throw std::invalid_argument("noise: stddev must be >= 0");
}

std::string NoiseSource::describe() const {
  return fmt::format("noise mean={} stddev={} seed={}", mean_, stddev_, seed_);
}

ReplaySource::ReplaySource(std::vector<Sample> samples, bool loop, std::string origin)
    : samples_(std::move(samples)), loop_(loop), origin_(std::move(origin)) {
  if (samples_.empty()) throw std::invalid_argument("replay: no samples");
  for (size_t i = 1; i < samples_.size(); ++i) {
    if (!(samples_[i].t > samples_[i - 1].t))
      throw std::invalid_argument("replay: times must be strictly increasing");
  }
}

namespace {
std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r'))
    s.remove_suffix(1);
  return s;
}
bool parse_double(std::string_view s, double& out) {
  s = trim(s);
  if (s.empty()) return false;
  if (s.front() == '+') s.remove_prefix(1);
  const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), out);
  return ec == std::errc() && ptr == s.data() + s.size() && std::isfinite(out);
}
}  // namespace

std::unique_ptr<ReplaySource> ReplaySource::from_csv(const std::string& path, bool loop) {
  // A recording is a regular file of bounded size (not a device such as /dev/zero).
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    throw std::runtime_error(fmt::format("{}: not a readable regular file", path));
  if (std::filesystem::file_size(path, ec) > kMaxReplayBytes)
    throw std::runtime_error(fmt::format("{}: larger than {} bytes", path, kMaxReplayBytes));
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(fmt::format("{}: cannot open file", path));
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return from_text(text, path, loop);
}

std::unique_ptr<ReplaySource> ReplaySource::from_text(std::string_view text_in,
                                                      const std::string& origin, bool loop) {
  // Errors name the file and line, never the line's content (the file may not be ours to show).
  std::vector<Sample> samples;
  int number = 0;
  while (!text_in.empty()) {
    const size_t eol = text_in.find('\n');
    const std::string_view line = text_in.substr(0, eol);
    text_in.remove_prefix(eol == std::string_view::npos ? text_in.size() : eol + 1);
    ++number;
    std::string_view text = trim(line);
    if (text.empty() || text.front() == '#') continue;
    const size_t comma = text.find(',');
    if (comma == std::string_view::npos)
      throw std::runtime_error(fmt::format("{}:{}: expected \"time_s,value\"", origin, number));
    Sample s{};
    const bool ok_t = parse_double(text.substr(0, comma), s.t);
    const bool ok_v = parse_double(text.substr(comma + 1), s.value);
    if (!ok_t || !ok_v) {
      if (samples.empty() && !ok_t && !ok_v) continue;  // a header row such as "time,value"
      throw std::runtime_error(fmt::format("{}:{}: not a number", origin, number));
    }
    if (!samples.empty() && !(s.t > samples.back().t))
      throw std::runtime_error(fmt::format("{}:{}: time {} is not after the previous row's {}",
                                           origin, number, s.t, samples.back().t));
    samples.push_back(s);
  }
  if (samples.empty()) throw std::runtime_error(fmt::format("{}: no samples", origin));
  return std::make_unique<ReplaySource>(std::move(samples), loop, origin);
}

double ReplaySource::sample(double t) {
  const Sample& first = samples_.front();
  const Sample& last = samples_.back();
  if (samples_.size() == 1 || t <= first.t) return first.value;
  if (t >= last.t) {
    if (!loop_) return last.value;
    const double span = last.t - first.t;
    t = first.t + std::fmod(t - first.t, span);
  }
  // Monotonic time moves the cursor forward; a wrap (loop) restarts it.
  if (t < samples_[cursor_].t) cursor_ = 0;
  while (cursor_ + 1 < samples_.size() && samples_[cursor_ + 1].t <= t) ++cursor_;
  if (cursor_ + 1 >= samples_.size()) return last.value;
  const Sample& a = samples_[cursor_];
  const Sample& b = samples_[cursor_ + 1];
  return a.value + (b.value - a.value) * (t - a.t) / (b.t - a.t);
}

std::string ReplaySource::describe() const {
  return fmt::format("replay file={} rows={} loop={}", origin_, samples_.size(), loop_);
}

LoopbackSource::LoopbackSource(const double* output, std::string output_name, double gain,
                               double offset)
    : affine_{output, gain, offset}, name_(std::move(output_name)) {
  if (output == nullptr) throw std::invalid_argument("loopback: no output channel");
}

std::string LoopbackSource::describe() const {
  return fmt::format("loopback output={} gain={} offset={}", name_, affine_.gain, affine_.offset);
}

PlantSource::PlantSource(const StateSpacePlant& plant, size_t index, std::string plant_name)
    : plant_(plant), index_(index), name_(std::move(plant_name)) {
  if (index >= plant.outputs()) throw std::invalid_argument("plant: output index out of range");
}

double PlantSource::sample(double) {
  return plant_.output(index_);
}

std::string PlantSource::describe() const {
  return fmt::format("plant name={} output={}", name_, index_);
}

}  // namespace rackcat::modules
