// The application cycle of the default rack (examples/default-rack.yaml: 27 modules, every
// card kind, sine/ramp/noise/constant and loopback sources) plus a state-space plant, in
// process. Target: < 5 µs per cycle (docs/PERFORMANCE.md "## modules").
#include <benchmark/benchmark.h>

#include <algorithm>
#include <filesystem>
#include <memory>
#include <vector>

#include "base/round_time.hpp"
#include "mdp/device.hpp"
#include "mdp/rack_config.hpp"
#include "modules/cards/analog_scale.hpp"
#include "modules/cards/rtd.hpp"
#include "modules/cards/thermocouple.hpp"
#include "modules/rack/rack.hpp"

using namespace rackcat;
using namespace rackcat::modules;

namespace {

struct Setup {
  double clock = 0.0;
  mdp::Device device;
  Rack rack;
  std::vector<uint8_t> sm2, sm3;

  Setup() : device(mdp::default_rack(), options()), rack(device, rack_options(&clock)) {
    const uint16_t tc = rack.driver_at(1, 15)->module().number;
    rack.set_source(
        tc, 0, "plant",
        {{"plant", "oven"}, {"a", "-0.1"}, {"b", "5"}, {"c", "1"}, {"inputs", "1.11.0"}});
    device.state_changed(EsmState::Init, EsmState::PreOp);
    device.state_changed(EsmState::PreOp, EsmState::SafeOp);
    device.state_changed(EsmState::SafeOp, EsmState::Op);
    sm2.assign(device.output_bytes(), 0x55);
    sm3.assign(device.input_bytes(), 0);
  }
  static mdp::DeviceOptions options() {
    mdp::DeviceOptions o;
    o.state_dir = (std::filesystem::temp_directory_path() / "rackcat-bench-modules").string();
    o.load_stored_parameters = false;
    return o;
  }
  static RackOptions rack_options(double* clock) {
    RackOptions o;
    o.clock = [clock] { return *clock; };
    return o;
  }
};

// The modules' share of a cycle: every driver reads its outputs and refreshes its inputs,
// sources and the plant advance, wiring faults and the exception tree are evaluated.
void BM_RackCycle(benchmark::State& state) {
  Setup s;
  for (auto _ : state) {
    s.clock += 0.001;
    s.rack.on_outputs(s.device);
    s.rack.before_inputs(s.device);
  }
  state.counters["modules"] = static_cast<double>(s.device.modules().size());
}
BENCHMARK(BM_RackCycle);

// The full application cycle as the ESC runs it: SM2 unpacked into the 0x7nnX objects, the
// drivers, then the 0x6nnX objects packed into SM3 (mdp process image included).
void BM_DeviceCycle(benchmark::State& state) {
  Setup s;
  for (auto _ : state) {
    s.clock += 0.001;
    s.device.write_outputs(s.sm2);
    s.device.read_inputs(s.sm3);
    benchmark::DoNotOptimize(s.sm3.data());
  }
  state.counters["sm2_bytes"] = static_cast<double>(s.sm2.size());
  state.counters["sm3_bytes"] = static_cast<double>(s.sm3.size());
}
BENCHMARK(BM_DeviceCycle);

// The encoder card (docs/ENCODER.md) alone in a rack: one CAE-10 on a 10 rev/s ramp with a
// master that counts its sign-of-life, so the cycle covers telegram in, sign-of-life check,
// sampling, position (round axis: 100 turns of 1000 units), velocity filter and telegram out.
void BM_EncoderCard(benchmark::State& state) {
  constexpr const char* kRack = R"(
rims:
  - rim: 1
    type: 6-slot
    slots:
      - slot: 1
        card: CAE-10
        channels:
          - {channel: 0, source: ramp, from: 0, to: 1000000, period_s: 100000}
)";
  double clock = 0.0;
  mdp::Device device(mdp::parse_rack_config(kRack, "<bench encoder>"), Setup::options());
  Rack rack(device, Setup::rack_options(&clock));
  coe::Object& settings = *device.dictionary().find(0x8000);
  settings.set_u(0x06, 100000);  // total range first (units x turns must cover it)
  settings.set_u(0x05, 1000);
  device.state_changed(EsmState::Init, EsmState::PreOp);
  device.state_changed(EsmState::PreOp, EsmState::SafeOp);
  device.state_changed(EsmState::SafeOp, EsmState::Op);
  std::vector<uint8_t> sm2(device.output_bytes(), 0), sm3(device.input_bytes(), 0);
  uint8_t ls = 0;
  for (auto _ : state) {
    clock += 0.001;
    ls = ls >= 15 ? 1 : static_cast<uint8_t>(ls + 1);
    sm2[1] = static_cast<uint8_t>(ls << 4 | 0x04);  // STW2_ENC: sign-of-life, bit 10
    device.write_outputs(sm2);
    device.read_inputs(sm3);
    benchmark::DoNotOptimize(sm3.data());
  }
  state.counters["sm3_bytes"] = static_cast<double>(sm3.size());
}
BENCHMARK(BM_EncoderCard);

void BM_ThermocoupleChannel(benchmark::State& state) {
  double t = 20.0;
  for (auto _ : state) {
    t = t > 1300.0 ? 20.0 : t + 0.37;
    benchmark::DoNotOptimize(tc_measure(TcType::K, t, 25.0, false));
  }
}
BENCHMARK(BM_ThermocoupleChannel);

void BM_RtdChannel(benchmark::State& state) {
  double t = -150.0;
  for (auto _ : state) {
    t = t > 800.0 ? -150.0 : t + 0.37;
    benchmark::DoNotOptimize(rtd_temperature(rtd_resistance(t)));
  }
}
BENCHMARK(BM_RtdChannel);

// The tiny rack of examples/tiny-rack.yaml (a relay card looped back to a digital input card),
// N of them in OP, each cycle the application work every slave's firmware does after a frame
// (SM2 into 0x7nnX and the drivers, then the drivers and 0x6nnX into SM3) in one firmware round
// (base/round_time.hpp), with the real clock, as `rackcat run --slaves N` runs it in OP.
// Issue 16's per-slave cost in process; scripts/callgrind_frame.sh counts its instructions.
constexpr const char* kTinyRack = R"(control_module:
  part_number: FI-CM0600-00
  serial_number: FI-CM0600-00-0001
rims:
  - rim: 1
    type: 6-slot
    unit_information: FUSION RIM 6
    slots:
      - {slot: 1, card: CRS-10}
      - {slot: 2, card: CDI-13, loopback: {rim: 1, slot: 1}}
)";

struct TinySlave {
  mdp::Device device;
  Rack rack;
  std::vector<uint8_t> sm2, sm3;
  TinySlave()
      : device(mdp::parse_rack_config(kTinyRack, "tiny-rack.yaml"), Setup::options()),
        rack(device) {
    device.state_changed(EsmState::Init, EsmState::PreOp);
    device.state_changed(EsmState::PreOp, EsmState::SafeOp);
    device.state_changed(EsmState::SafeOp, EsmState::Op);
    sm2.assign(device.output_bytes(), 0);
    sm3.assign(device.input_bytes(), 0);
  }
};

// One round over every slave (not inlined: scripts/callgrind_app.sh counts its instructions).
[[gnu::noinline]] void tiny_rack_round(std::vector<std::unique_ptr<TinySlave>>& slaves,
                                       uint8_t pattern) {
  const base::RoundTime::Scope round;
  for (auto& s : slaves) {
    std::fill(s->sm2.begin(), s->sm2.end(), pattern);
    s->device.write_outputs(s->sm2);
    s->device.read_inputs(s->sm3);
    benchmark::DoNotOptimize(s->sm3.data());
  }
}

void BM_TinyRackRound(benchmark::State& state) {
  const auto n = static_cast<size_t>(state.range(0));
  std::vector<std::unique_ptr<TinySlave>> slaves;
  for (size_t i = 0; i < n; ++i) slaves.push_back(std::make_unique<TinySlave>());
  uint8_t pattern = 0;
  for (auto _ : state) tiny_rack_round(slaves, ++pattern);
  if (slaves[0]->sm3.empty() || slaves[0]->sm2.empty()) state.SkipWithError("no process data");
  state.counters["slaves"] = static_cast<double>(n);
  state.counters["ns_per_slave"] =
      benchmark::Counter(static_cast<double>(state.iterations()) * static_cast<double>(n),
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_TinyRackRound)->Arg(1)->Arg(16)->Arg(199)->Unit(benchmark::kMicrosecond);

// The same rounds with the master repeating its output data, as a cyclic master does while
// nothing changes (op_bench's replay): what the application skips when its outputs are the
// ones it already drives (issue 16). The inputs are still sampled every round.
void BM_TinyRackRoundSteady(benchmark::State& state) {
  const auto n = static_cast<size_t>(state.range(0));
  std::vector<std::unique_ptr<TinySlave>> slaves;
  for (size_t i = 0; i < n; ++i) slaves.push_back(std::make_unique<TinySlave>());
  for (auto _ : state) tiny_rack_round(slaves, 0x5A);
  if (slaves[0]->sm3.empty() || slaves[0]->sm2.empty()) state.SkipWithError("no process data");
  state.counters["slaves"] = static_cast<double>(n);
  state.counters["ns_per_slave"] =
      benchmark::Counter(static_cast<double>(state.iterations()) * static_cast<double>(n),
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_TinyRackRoundSteady)->Arg(16)->Arg(199)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
