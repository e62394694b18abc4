// ns per frame through an in-process Segment on the real clock (SteadyClock, one clock read
// per frame included): SOEM's cyclic frame (LRW over all process data + FRMW 0x0910) for 1,
// 16 and 128 slaves in OP, a BRD, and a mailbox round trip. Target: < 1 µs per slave per frame.
#include <benchmark/benchmark.h>

#include <cstring>

#include "tests/ecat/test_master.hpp"

namespace rackcat::ecat::test {
namespace {

// SOEM's cyclic frame for n slaves of the test line: LRW over all process data + FRMW 0x0910
// (DC on), or the LRW alone (no DC: pysoem's frame in scripts/op_bench.py).
std::vector<uint8_t> cyclic_frame(size_t n, bool dc = true) {
  FrameBuilder b;
  b.add_logical(Command::Lrw, 0, std::vector<uint8_t>(n * (kOutputBytes + kInputBytes), 0x5A));
  if (dc) b.add(Command::Frmw, Line::station(0), 0x0910, std::vector<uint8_t>(8, 0));
  return b.build();
}

// Runs the frame through the segment once per iteration, each time a fresh copy as from the
// wire, and checks the LRW's working counter (read and written by every slave).
void run_cyclic_frames(benchmark::State& state, Line& line, size_t n, bool dc = true) {
  const std::vector<uint8_t> frame = cyclic_frame(n, dc);
  std::vector<uint8_t> work = frame;
  for (auto _ : state) {
    std::memcpy(work.data(), frame.data(), frame.size());
    benchmark::DoNotOptimize(line.segment->process(work));
  }
  const uint16_t wkc = static_cast<uint16_t>(work[16 + 10 + n * 10] | work[16 + 11 + n * 10] << 8);
  if (wkc != 3 * n) state.SkipWithError("unexpected LRW working counter");
  state.counters["ns_per_slave"] =
      benchmark::Counter(static_cast<double>(state.iterations()) * static_cast<double>(n),
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

void BM_CyclicLrwFrmw(benchmark::State& state) {
  const auto n = static_cast<size_t>(state.range(0));
  Line line(n, {}, &SteadyClock::instance());
  line.to_op();
  run_cyclic_frames(state, line, n);
  state.counters["slaves"] = static_cast<double>(n);
}
BENCHMARK(BM_CyclicLrwFrmw)->Arg(1)->Arg(16)->Arg(128)->Unit(benchmark::kNanosecond);

// The reply path alone, as the event loop runs it (deferred firmware, ecat/segment.hpp):
// what the master's cyclic LRW + FRMW waits for between receive and send when the slaves'
// firmware runs between frames. The firmware work is left pending (never run here), so each
// ESC sees its SM2 written and SM3 read every frame without a new buffer from the firmware.
void BM_CyclicLrwReplyPath(benchmark::State& state) {
  const auto n = static_cast<size_t>(state.range(0));
  Line line(n, {}, &SteadyClock::instance());
  line.to_op();
  line.segment->set_deferred_firmware(true);
  run_cyclic_frames(state, line, n);
}
BENCHMARK(BM_CyclicLrwReplyPath)->Arg(1)->Arg(16)->Arg(128)->Arg(199)->Unit(benchmark::kNanosecond);

// The same without the FRMW: the frame of a master without DC, one LRW (the segment's path
// for a frame of one logical datagram).
void BM_CyclicLrwOnlyReplyPath(benchmark::State& state) {
  const auto n = static_cast<size_t>(state.range(0));
  Line line(n, {}, &SteadyClock::instance());
  line.to_op();
  line.segment->set_deferred_firmware(true);
  run_cyclic_frames(state, line, n, false);
}
BENCHMARK(BM_CyclicLrwOnlyReplyPath)
    ->Arg(1)
    ->Arg(16)
    ->Arg(128)
    ->Arg(199)
    ->Unit(benchmark::kNanosecond);

// One slave's outputs in a line of N in OP (an LWR that only the first slave's output FMMU
// meets): what every other ESC spends on a logical datagram that is not theirs.
void BM_LwrOneSlaveOfMany(benchmark::State& state) {
  const auto n = static_cast<size_t>(state.range(0));
  Line line(n, {}, &SteadyClock::instance());
  line.to_op();
  FrameBuilder b;
  b.add_logical(Command::Lwr, 0, std::vector<uint8_t>(kOutputBytes, 0x5A));
  const std::vector<uint8_t> frame = b.build();
  std::vector<uint8_t> work = frame;
  for (auto _ : state) {
    std::memcpy(work.data(), frame.data(), frame.size());
    benchmark::DoNotOptimize(line.segment->process(work));
  }
  const auto reply = decode(work);
  if (reply.empty() || reply[0].wkc != 1) state.SkipWithError("unexpected LWR working counter");
  state.counters["slaves"] = static_cast<double>(n);
}
BENCHMARK(BM_LwrOneSlaveOfMany)->Arg(16)->Arg(128)->Unit(benchmark::kNanosecond);

void BM_Brd(benchmark::State& state) {
  const auto n = static_cast<size_t>(state.range(0));
  Line line(n, {}, &SteadyClock::instance());
  line.to_preop();
  FrameBuilder b;
  b.add(Command::Brd, 0, 0x0130, {0, 0});
  const std::vector<uint8_t> frame = b.build();
  std::vector<uint8_t> work = frame;
  for (auto _ : state) {
    std::memcpy(work.data(), frame.data(), frame.size());
    benchmark::DoNotOptimize(line.segment->process(work));
  }
}
BENCHMARK(BM_Brd)->Arg(1)->Arg(16)->Unit(benchmark::kNanosecond);

void BM_MailboxEchoRoundTrip(benchmark::State& state) {
  Line line(1, {}, &SteadyClock::instance());
  line.to_preop();
  // The master counts its requests 1..7 (ETG.1000.4 §5.6): a repeated counter with the same
  // bytes would be a double write, which the slave drops.
  std::vector<std::vector<uint8_t>> writes;
  for (uint8_t c = 1; c <= 7; ++c) {
    std::vector<uint8_t> request(kMbxSize, 0);
    request[0] = 10;
    request[5] = static_cast<uint8_t>(c << 4 | 0x03);
    FrameBuilder write;
    write.add(Command::Fpwr, 0x1001, kMbxOutStart, request);
    writes.push_back(write.build());
  }
  FrameBuilder read;
  read.add(Command::Fprd, 0x1001, kMbxInStart, std::vector<uint8_t>(kMbxSize, 0));
  const auto rf = read.build();
  std::vector<uint8_t> work(std::max(writes[0].size(), rf.size()));
  size_t n = 0;
  for (auto _ : state) {
    const auto& wf = writes[n++ % writes.size()];
    std::memcpy(work.data(), wf.data(), wf.size());
    line.segment->process(std::span<uint8_t>(work.data(), wf.size()));
    std::memcpy(work.data(), rf.data(), rf.size());
    line.segment->process(std::span<uint8_t>(work.data(), rf.size()));
  }
  if (line.app(0).mailbox_requests != static_cast<int>(state.iterations()))
    state.SkipWithError("mailbox lost");
}
BENCHMARK(BM_MailboxEchoRoundTrip)->Unit(benchmark::kNanosecond);

}  // namespace
}  // namespace rackcat::ecat::test

BENCHMARK_MAIN();
