// What one master cycle costs rackcat per slave, whole stack, in process: N tiny racks
// (examples/tiny-rack.yaml, built as `rackcat run --slaves N --config examples/tiny-rack.yaml`
// builds them: apps::RackSlave behind an ecat::Segment on SteadyClock, firmware deferred as in
// ecat::Runner), brought to OP by a test master the way op_bench's pysoem master configures
// them (mailbox SyncManagers from the SII, SM2/SM3 and one FMMU each, outputs of all slaves
// first, process-data watchdog off, SAFEOP, one cycle, OP). Each iteration is what the event
// loop does for one cycle: Segment::process of the master's LRW, then Segment::after_frame
// (the firmware and application round the reply leaves behind, which the next frame waits for
// when frames come back to back). Issue 16's per-slave cost on the wire, without the socket.
//
//   BM_RackLineCycle/N/dc        outputs change every frame
//   BM_RackLineCycleSteady/N/dc  the master repeats its outputs (op_bench's replay)
//   BM_RackLinePass/N            the same cycle, only its frames timed (not the round after
//                                them): what a master that paces its cycles waits for
// N = 16, 199 (pysoem's largest), 256 and 1,024 (ethercrab's, op_bench from 200 slaves on):
// an image above 1,100 bytes goes in several frames of one LRW datagram each, as ethercrab
// cuts it (1,024: two frames per cycle), sent back to back as SOEM sends its frames: one round
// after the last (the event loop's bursts, ecat/host/event_loop.hpp).
// dc = 0: the LRW alone, the frame pysoem sends without config_dc (op_bench); dc = 1: with the
// FRMW 0x0910 that SOEM adds to the frame once DC is configured (docs/INTEROP.md).
// scripts/callgrind_line.sh counts their instructions per slave.
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "apps/rack_slave/rack_loading.hpp"
#include "apps/rack_slave/rack_slave.hpp"
#include "base/little_endian.hpp"
#include "tests/ecat/test_master.hpp"

namespace rackcat::ecat::test {
namespace {

// SII category "SyncManager" (ETG.2010 Table 2 category 41, Table 15 entries of 8 bytes:
// start, length, control, status, enable, type) as a master reads it to configure SM2/SM3.
struct SiiSyncManager {
  uint16_t start = 0;
  uint8_t control = 0;
};
constexpr uint16_t kSiiCategorySyncManager = 41;
constexpr uint16_t kSiiCategoryEnd = 0xFFFF;
constexpr size_t kSiiFirstCategoryWord = 0x40;
constexpr uint8_t kSiiTypeOutputs = 3;
constexpr uint8_t kSiiTypeInputs = 4;

std::optional<SiiSyncManager> sii_sync_manager(std::span<const uint8_t> sii, uint8_t type) {
  size_t at = kSiiFirstCategoryWord * 2;
  while (at + 4 <= sii.size()) {
    const uint16_t category = le::get16(&sii[at]);
    const size_t bytes = static_cast<size_t>(le::get16(&sii[at + 2])) * 2;
    if (category == kSiiCategoryEnd || at + 4 + bytes > sii.size()) break;
    if (category == kSiiCategorySyncManager) {
      for (size_t e = at + 4; e + 8 <= at + 4 + bytes; e += 8) {
        if (sii[e + 7] == type) return SiiSyncManager{le::get16(&sii[e]), sii[e + 4]};
      }
    }
    at += 4 + bytes;
  }
  return std::nullopt;
}

// One FMMU as a master writes it at 0x0600 + 16n (ETG.1000.4 §6.6): logical start, length,
// start bit 0, stop bit 7, physical start, bit 0, type (1 read, 2 write), enabled.
std::vector<uint8_t> fmmu(uint32_t logical, uint16_t length, uint16_t physical, uint8_t type) {
  std::vector<uint8_t> f(16, 0);
  le::put32(&f[0], logical);
  le::put16(&f[4], length);
  f[7] = 7;
  le::put16(&f[8], physical);
  f[11] = type;
  f[12] = 0x01;
  return f;
}

// ethercrab's LRW datagram size (interop/ethercrab PDU_PAYLOAD): op_bench's replay above 199
// slaves, where ethercrab configures the line.
constexpr size_t kLrwChunk = 1100;

// `rackcat run --slaves N --config examples/tiny-rack.yaml`'s line, in OP.
class RackLine {
 public:
  explicit RackLine(size_t n)
      : state_dir_(std::filesystem::temp_directory_path() /
                   ("rackcat-bench-rack-line-" + std::to_string(::getpid()))) {
    const auto config = apps::load_rack_or_report(RACKCAT_SOURCE_DIR "/examples/tiny-rack.yaml");
    if (!config) return;
    std::vector<Application*> line;
    for (size_t i = 0; i < n; ++i) {
      racks_.push_back(
          std::make_unique<apps::RackSlave>(*config, state_dir_.string(), static_cast<int>(i)));
      line.push_back(racks_.back().get());
    }
    segment_ = std::make_unique<Segment>(line, SteadyClock::instance());
    master_ = std::make_unique<TestMaster>(*segment_);
    const ProcessDataSizes sizes = racks_[0]->process_data_sizes();
    outputs_ = sizes.outputs;
    inputs_ = sizes.inputs;
  }
  RackLine(const RackLine&) = delete;
  RackLine& operator=(const RackLine&) = delete;
  ~RackLine() {
    segment_.reset();
    racks_.clear();
    std::error_code ignored;
    std::filesystem::remove_all(state_dir_, ignored);
  }

  // Empty when the line did not reach OP; else the reason it did not.
  std::string to_op() {
    if (!segment_) return "tiny-rack.yaml did not load";
    const auto sm2 = sii_sync_manager(racks_[0]->eeprom(), kSiiTypeOutputs);
    const auto sm3 = sii_sync_manager(racks_[0]->eeprom(), kSiiTypeInputs);
    if (!sm2 || !sm3 || outputs_ == 0 || inputs_ == 0) return "no process data in the SII";
    master_->config_init();
    const size_t n = racks_.size();
    for (size_t k = 0; k < n; ++k) {
      const uint16_t station = Line::station(k);
      auto sm = [](uint16_t start, uint16_t length, uint8_t control) {
        return std::vector<uint8_t>{static_cast<uint8_t>(start),
                                    static_cast<uint8_t>(start >> 8),
                                    static_cast<uint8_t>(length),
                                    static_cast<uint8_t>(length >> 8),
                                    control,
                                    0x00,
                                    0x01,
                                    0x00};
      };
      master_->fpwr(station, 0x0810, sm(sm2->start, outputs_, sm2->control));
      master_->fpwr(station, 0x0818, sm(sm3->start, inputs_, sm3->control));
      master_->fpwr(station, 0x0600,
                    fmmu(static_cast<uint32_t>(k * outputs_), outputs_, sm2->start, 2));
      master_->fpwr(
          station, 0x0610,
          fmmu(static_cast<uint32_t>(n * outputs_ + k * inputs_), inputs_, sm3->start, 1));
      master_->fpwr16(station, 0x0420, 0);  // process-data watchdog off, as op_bench's master
    }
    for (size_t k = 0; k < n; ++k) {
      if ((master_->request_state(Line::station(k), 0x04) & 0x1F) != 0x04) return "no SAFEOP";
    }
    for (std::vector<uint8_t> work : cycle(0, false)) {
      segment_->process(work);
      segment_->after_frame();
    }
    for (size_t k = 0; k < n; ++k) {
      if ((master_->request_state(Line::station(k), 0x08) & 0x1F) != 0x08) return "no OP";
    }
    return {};
  }

  // The master's cyclic frames: LRW over every slave's outputs (all `value`) and inputs, cut
  // into datagrams of at most kLrwChunk bytes, one per frame, as ethercrab sends an image
  // larger than one frame (1,024 slaves: two); plus FRMW 0x0910 from the first slave (the DC
  // reference) in the first frame with `dc`.
  std::vector<std::vector<uint8_t>> cycle(uint8_t value, bool dc) const {
    std::vector<uint8_t> image(racks_.size() * (outputs_ + inputs_), 0);
    std::memset(image.data(), value, racks_.size() * outputs_);
    std::vector<std::vector<uint8_t>> frames;
    for (size_t at = 0; at < image.size(); at += kLrwChunk) {
      const size_t end = std::min(image.size(), at + kLrwChunk);
      FrameBuilder b;
      b.add_logical(Command::Lrw, static_cast<uint32_t>(at),
                    std::vector<uint8_t>(image.begin() + static_cast<long>(at),
                                         image.begin() + static_cast<long>(end)));
      if (dc && at == 0) b.add(Command::Frmw, Line::station(0), 0x0910, std::vector<uint8_t>(8, 0));
      frames.push_back(b.build());
    }
    return frames;
  }
  // A master that does not combine them into an LRW: LWR of every slave's outputs (all
  // `value`), then, in a frame of its own, LRD of every slave's inputs.
  std::vector<std::vector<uint8_t>> split_frames(uint8_t value) const {
    FrameBuilder lwr;
    lwr.add_logical(Command::Lwr, 0, std::vector<uint8_t>(racks_.size() * outputs_, value));
    FrameBuilder lrd;
    lrd.add_logical(Command::Lrd, static_cast<uint32_t>(racks_.size() * outputs_),
                    std::vector<uint8_t>(racks_.size() * inputs_, 0));
    return {lwr.build(), lrd.build()};
  }
  // The first datagram's working counter in a frame that came back (the LRW, LWR or LRD).
  uint16_t first_wkc(const std::vector<uint8_t>& f) const { return decode(f).at(0).wkc; }
  Segment& segment() { return *segment_; }
  size_t size() const { return racks_.size(); }

 private:
  std::filesystem::path state_dir_;
  std::vector<std::unique_ptr<apps::RackSlave>> racks_;
  std::unique_ptr<Segment> segment_;
  std::unique_ptr<TestMaster> master_;
  uint16_t outputs_ = 0;
  uint16_t inputs_ = 0;
};

// One master cycle as the event loop handles it (not inlined: scripts/callgrind_line.sh counts
// its instructions): the cycle's frames from the wire, each processed in place (the replies),
// then the firmware and application round of every slave they passed - once, as the loop runs
// it after the last frame of a burst (a master sending a large image's frames back to back).
[[gnu::noinline]] void rack_line_cycle(Segment& segment,
                                       std::span<const std::vector<uint8_t>> from_wire,
                                       std::span<std::vector<uint8_t>> work) {
  for (size_t f = 0; f < from_wire.size(); ++f) {
    std::memcpy(work[f].data(), from_wire[f].data(), from_wire[f].size());
    benchmark::DoNotOptimize(segment.process(work[f]));
  }
  segment.after_frame();
}

// N tiny racks in OP with the firmware deferred as the event loop runs it; nullptr (and the
// benchmark skipped with the reason) when the test master could not bring them there.
std::unique_ptr<RackLine> line_in_op(benchmark::State& state, size_t n) {
  auto line = std::make_unique<RackLine>(n);
  if (const std::string failed = line->to_op(); !failed.empty()) {
    state.SkipWithError(failed.c_str());
    return nullptr;
  }
  line->segment().set_deferred_firmware(true);
  return line;
}

void run(benchmark::State& state, bool changing) {
  const auto n = static_cast<size_t>(state.range(0));
  const bool dc = state.range(1) != 0;
  const std::unique_ptr<RackLine> in_op = line_in_op(state, n);
  if (!in_op) return;
  RackLine& line = *in_op;
  const std::vector<std::vector<uint8_t>> cycles[2] = {line.cycle(0x5A, dc),
                                                       line.cycle(changing ? 0xA5 : 0x5A, dc)};
  std::vector<std::vector<uint8_t>> work = cycles[0];
  size_t k = 0;
  for (auto _ : state) rack_line_cycle(line.segment(), cycles[k++ & 1], work);
  size_t wkc = 0;
  for (const auto& f : work) wkc += line.first_wkc(f);
  if (wkc != 3 * n) state.SkipWithError("unexpected LRW working counter");
  state.counters["slaves"] = static_cast<double>(n);
  state.counters["frames"] = static_cast<double>(work.size());
  state.counters["ns_per_slave"] =
      benchmark::Counter(static_cast<double>(state.iterations()) * static_cast<double>(n),
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

// The frames of a steady cycle (no DC) timed alone: each round still runs after them, untimed,
// and leaves the caches as it does on the wire, where a paced master's next frame finds the
// round done (docs/PERFORMANCE.md: paced at 1 ms the reply is the frames' pass alone).
void BM_RackLinePass(benchmark::State& state) {
  const auto n = static_cast<size_t>(state.range(0));
  const std::unique_ptr<RackLine> in_op = line_in_op(state, n);
  if (!in_op) return;
  RackLine& line = *in_op;
  const std::vector<std::vector<uint8_t>> frames = line.cycle(0x5A, false);
  std::vector<std::vector<uint8_t>> work = frames;
  for (auto _ : state) {
    for (size_t f = 0; f < frames.size(); ++f)
      std::memcpy(work[f].data(), frames[f].data(), frames[f].size());
    const auto start = std::chrono::steady_clock::now();
    for (auto& f : work) benchmark::DoNotOptimize(line.segment().process(f));
    const auto stop = std::chrono::steady_clock::now();
    line.segment().after_frame();
    state.SetIterationTime(std::chrono::duration<double>(stop - start).count());
  }
  size_t wkc = 0;
  for (const auto& f : work) wkc += line.first_wkc(f);
  if (wkc != 3 * n) state.SkipWithError("unexpected LRW working counter");
  state.counters["slaves"] = static_cast<double>(n);
}
BENCHMARK(BM_RackLinePass)
    ->Arg(16)
    ->Arg(199)
    ->Arg(256)
    ->Arg(1024)
    ->UseManualTime()
    ->Unit(benchmark::kMicrosecond);

void BM_RackLineCycle(benchmark::State& state) {
  run(state, true);
}
void BM_RackLineCycleSteady(benchmark::State& state) {
  run(state, false);
}
// One master cycle of LWR + LRD (two frames, each followed by its round), the outputs repeated.
void BM_RackLineLwrLrdSteady(benchmark::State& state) {
  const auto n = static_cast<size_t>(state.range(0));
  const std::unique_ptr<RackLine> in_op = line_in_op(state, n);
  if (!in_op) return;
  RackLine& line = *in_op;
  const std::vector<std::vector<uint8_t>> frames = line.split_frames(0x5A);
  std::vector<std::vector<uint8_t>> work = frames;
  for (auto _ : state) {
    // Each frame sent once the previous reply came: each followed by its round.
    rack_line_cycle(line.segment(), {&frames[0], 1}, {&work[0], 1});
    rack_line_cycle(line.segment(), {&frames[1], 1}, {&work[1], 1});
  }
  if (line.first_wkc(work[0]) != n || line.first_wkc(work[1]) != n) {
    state.SkipWithError("unexpected LWR/LRD working counter");
  }
  state.counters["slaves"] = static_cast<double>(n);
  state.counters["ns_per_slave"] =
      benchmark::Counter(static_cast<double>(state.iterations()) * static_cast<double>(n),
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_RackLineLwrLrdSteady)->Arg(16)->Arg(199)->Unit(benchmark::kMicrosecond);

BENCHMARK(BM_RackLineCycle)
    ->ArgsProduct({{16, 199, 256, 1024}, {0, 1}})
    ->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_RackLineCycleSteady)
    ->ArgsProduct({{16, 199, 256, 1024}, {0, 1}})
    ->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace rackcat::ecat::test

BENCHMARK_MAIN();
