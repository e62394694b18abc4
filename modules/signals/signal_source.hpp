// Signal models for input channels. Every input channel of the emulated rack has one source
// that is sampled on the process-data cycle (free run, SM event or SYNC0): constant, ramp,
// sine, Gaussian noise from a seeded PRNG, replay of a CSV recording, loopback from an output
// channel, one output of a linear state-space plant, or a monotonic-clock time stamp.
//
// Units are physical: volts for analog channels, °C for thermocouple and RTD channels,
// 0/1 for digital channels (>= 0.5 reads as 1).
//
// Sources are built when the rack starts or when the control API changes them (never on the
// cyclic path); sample() never allocates. Oversampled cards call sample() several times per
// cycle at sub-cycle times, so sources are functions of absolute time where possible.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace rackcat::modules {

class StateSpacePlant;

// Aligned to 32 bytes: the vtable pointer and the first fields sample() reads (a loopback's
// output, gain and offset) never straddle two cache lines, so sampling a source costs one line
// (issue 16: in a line of racks every source is sampled and evicted again each frame).
class alignas(32) Source {
 public:
  virtual ~Source() = default;
  // The value at t seconds since the rack started. Calls come with non-decreasing t.
  virtual double sample(double t) = 0;
  // One line for `rackcat ctl list`, e.g. "sine amplitude=5 frequency=1 offset=0".
  virtual std::string describe() const = 0;
  // False when the value can only change from one cycle to the next (constant, loopback,
  // plant): oversampled cards then sample once per cycle instead of eight times.
  virtual bool varies_within_cycle() const { return true; }

  // A source whose value is gain * *x + offset, x a value that stays in place while the source
  // lives (a loopback's output channel; a constant over a fixed zero). The card keeps these three
  // next to its channels and samples without touching the source object (issue 16: in a line of
  // racks each source object is one more cache line per frame). x == nullptr: call sample().
  struct Affine {
    const double* x = nullptr;
    double gain = 1.0;
    double offset = 0.0;
    double value() const { return gain * *x + offset; }
  };
  virtual Affine affine() const { return {}; }
};

class ConstantSource final : public Source {
 public:
  explicit ConstantSource(double value) : value_(value) {}
  double sample(double) override { return value_; }
  std::string describe() const override;
  bool varies_within_cycle() const override { return false; }
  Affine affine() const override { return {&kZero, 0.0, value_}; }

 private:
  static constexpr double kZero = 0.0;
  double value_;
};

// Sawtooth: from `from` to `to` over `period_s`, then starts again.
class RampSource final : public Source {
 public:
  RampSource(double from, double to, double period_s);
  double sample(double t) override;
  std::string describe() const override;

 private:
  double from_, to_, period_;
};

class SineSource final : public Source {
 public:
  SineSource(double amplitude, double frequency_hz, double offset, double phase_rad = 0.0);
  double sample(double t) override;
  std::string describe() const override;

 private:
  double amplitude_, frequency_, offset_, phase_;
};

// Time stamps for measuring how old input data is when it reaches a master: the value is the
// ±10 V code (docs/MODULES.md) of the CLOCK_MONOTONIC time in ticks of `tick_us`, modulo 65535,
// as code = ticks mod 65535 - 32767 (so -32767..32767, every code exact). A master on the same
// machine (same monotonic clock) decodes it and subtracts it from its own receive time: the
// age of the sample across RIM, CAN bus, control module and EtherCAT. It ignores the rack time
// on purpose; it is the one source that is not reproducible from run to run.
class ClockSource final : public Source {
 public:
  explicit ClockSource(double tick_us);
  double sample(double) override;
  std::string describe() const override;
  // The code this source gives at CLOCK_MONOTONIC time `monotonic_ns` (tests, decoders).
  int16_t code_at(int64_t monotonic_ns) const;

 private:
  int64_t tick_ns_;
};

// xoshiro256** (Blackman & Vigna), seeded through splitmix64: the same seed gives the same
// sequence on every platform, unlike std::normal_distribution.
class Prng {
 public:
  explicit Prng(uint64_t seed);
  uint64_t next();
  // Uniform in (0, 1].
  double uniform();
  // Standard normal (Box-Muller, second value cached).
  double gaussian();

 private:
  uint64_t s_[4];
  double spare_ = 0.0;
  bool has_spare_ = false;
};

class NoiseSource final : public Source {
 public:
  NoiseSource(double mean, double stddev, uint64_t seed);
  double sample(double) override { return mean_ + stddev_ * prng_.gaussian(); }
  std::string describe() const override;

 private:
  double mean_, stddev_;
  uint64_t seed_;
  Prng prng_;
};

// Replays a recording loaded once from a CSV file of "time_s,value" rows (optional header
// row, '#' comments, times strictly increasing). Linear interpolation between rows; after the
// last row it loops (loop = true) or holds the last value.
class ReplaySource final : public Source {
 public:
  struct Sample {
    double t;
    double value;
  };
  ReplaySource(std::vector<Sample> samples, bool loop, std::string origin = {});
  static constexpr uintmax_t kMaxReplayBytes = 64u << 20;
  // Throws std::runtime_error("<path>:<line>: <problem>") on a bad file.
  static std::unique_ptr<ReplaySource> from_csv(const std::string& path, bool loop);
  // The same from the file's content, read by the caller (below a FileRoot); `origin` names
  // it in errors, which never quote the content.
  static std::unique_ptr<ReplaySource> from_text(std::string_view text, const std::string& origin,
                                                 bool loop);

  double sample(double t) override;
  std::string describe() const override;
  const std::vector<Sample>& samples() const { return samples_; }

 private:
  std::vector<Sample> samples_;
  bool loop_;
  std::string origin_;
  size_t cursor_ = 0;  // last segment used: sample() is O(1) for monotonic t
};

// Reads an output channel's live value (wired loopback): value = gain * output + offset.
class LoopbackSource final : public Source {
 public:
  LoopbackSource(const double* output, std::string output_name, double gain = 1.0,
                 double offset = 0.0);
  double sample(double) override { return affine_.value(); }
  std::string describe() const override;
  bool varies_within_cycle() const override { return false; }
  Affine affine() const override { return affine_; }

 private:
  // What sample() reads next to the vtable pointer (the aligned first 32 bytes), the name
  // last: one cache line per sample in a line of racks (issue 16).
  Affine affine_;  // x: the output channel's value
  std::string name_;
};

// Output `index` of a plant stepped by the rack once per cycle before the inputs are sampled.
class PlantSource final : public Source {
 public:
  PlantSource(const StateSpacePlant& plant, size_t index, std::string plant_name);
  double sample(double) override;
  std::string describe() const override;
  bool varies_within_cycle() const override { return false; }

 private:
  const StateSpacePlant& plant_;
  size_t index_;
  std::string name_;
};

}  // namespace rackcat::modules
