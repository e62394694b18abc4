// What an FoE transfer of parameters.bin (docs/FOE.md) costs the device thread, against the
// disk work the background worker now does for it (it ran on the device thread until session
// 8, stalling every slave's frames: a SOEM master drops a reply later than 2 ms):
// - BM_ParameterFoeRestoreDeviceThread: write request, every Data and the last Data's Busy
//   answer (the file checked like SDO writes) — the device thread's part of a restore; the
//   wait for the worker and the final Ack (which applies the set) are outside the timing.
// - BM_ParameterFoeReadDeviceThread: the read request (deferred) and, once the worker has the
//   file, the poll that sends Data 1 plus the Acks of the rest.
// - BM_ParameterFileSave / BM_ParameterFileLoad: the worker's part (write, fsync, rename, fsync
//   of the directory / read and check), what the device thread used to wait for.
// The state directory is RACKCAT_BENCH_DIR (default /var/tmp/rackcat-bench-parameter-foe): put
// it on a real disk, fsync on tmpfs costs nothing.
#include <benchmark/benchmark.h>

#include <chrono>
#include <cstdlib>
#include <string>
#include <thread>
#include <vector>

#include "base/little_endian.hpp"
#include "foe/foe_header.hpp"
#include "mdp/device.hpp"
#include "mdp/parameter_store.hpp"

namespace {

using namespace rackcat;
using Bytes = std::vector<uint8_t>;

constexpr uint32_t kPassword = 0x52434657;  // the default FoE password (docs/FOE.md)
constexpr size_t kMailboxData = 122;        // a 128-byte mailbox minus its header
constexpr size_t kChunk = kMailboxData - foe::FoeHeader::kSize;

std::string bench_dir(const std::string& leaf) {
  const char* env = std::getenv("RACKCAT_BENCH_DIR");
  return std::string(env && *env ? env : "/var/tmp/rackcat-bench-parameter-foe") + "/" + leaf;
}

// The master's side of FoE (ETG.1000.6 §5.8): header OpCode, reserved, UINT32, then data.
size_t send(mdp::Device& d, foe::OpCode op, uint32_t value, std::span<const uint8_t> data,
            Bytes& request, Bytes& reply) {
  request.resize(foe::FoeHeader::kSize);
  foe::FoeHeader{static_cast<uint8_t>(op), value}.encode(request);
  request.insert(request.end(), data.begin(), data.end());
  reply.resize(kMailboxData);
  return d.foe_request(request, kMailboxData, reply).length;
}

const Bytes kName = {'p', 'a', 'r', 'a', 'm', 'e', 't', 'e', 'r', 's', '.', 'b', 'i', 'n'};

std::unique_ptr<mdp::Device> preop_device(const std::string& leaf) {
  mdp::DeviceOptions o;
  o.load_stored_parameters = false;
  o.state_dir = bench_dir(leaf);
  auto d = std::make_unique<mdp::Device>(mdp::default_rack(), o);
  d->state_changed(EsmState::Init, EsmState::PreOp);
  return d;
}

// Polls until the deferred reply comes (untimed set-up); its length.
size_t wait_reply(mdp::Device& d, Bytes& reply) {
  reply.resize(kMailboxData);
  size_t n = d.foe_poll(reply);
  while (n == 0) {
    std::this_thread::sleep_for(std::chrono::microseconds(50));
    n = d.foe_poll(reply);
  }
  return n;
}

// The device's parameters.bin, read over FoE (untimed set-up).
Bytes read_file(mdp::Device& d) {
  Bytes req, reply, file;
  size_t n = send(d, foe::OpCode::ReadRequest, kPassword, kName, req, reply);
  if (n == 0) n = wait_reply(d, reply);
  for (uint32_t packet = 1;; ++packet) {
    file.insert(file.end(), reply.begin() + 6, reply.begin() + static_cast<long>(n));
    const bool last = n < kMailboxData;
    n = send(d, foe::OpCode::Ack, packet, {}, req, reply);
    if (last) return file;
  }
}

void BM_ParameterFoeRestoreDeviceThread(benchmark::State& state) {
  auto source = preop_device("source");
  const Bytes file = read_file(*source);
  auto d = preop_device("replacement");
  Bytes req, reply;
  for (auto _ : state) {
    send(*d, foe::OpCode::WriteRequest, kPassword, kName, req, reply);
    uint32_t packet = 0;
    for (size_t at = 0;;) {
      const size_t n = std::min(kChunk, file.size() - at);
      send(*d, foe::OpCode::Data, ++packet, {file.data() + at, n}, req, reply);
      at += n;
      if (n < kChunk) break;
    }
    state.PauseTiming();
    // The master repeats the last Data after each Busy until the Ack (the set is applied then).
    while (reply[0] == static_cast<uint8_t>(foe::OpCode::Busy)) {
      std::this_thread::sleep_for(std::chrono::microseconds(50));
      send(*d, foe::OpCode::Data, packet, {}, req, reply);
    }
    if (reply[0] != static_cast<uint8_t>(foe::OpCode::Ack)) state.SkipWithError("restore refused");
    state.ResumeTiming();
  }
  state.counters["file_bytes"] = static_cast<double>(file.size());
}
BENCHMARK(BM_ParameterFoeRestoreDeviceThread)->Unit(benchmark::kMicrosecond);

void BM_ParameterFoeReadDeviceThread(benchmark::State& state) {
  {
    auto source = preop_device("read-source");
    const Bytes file = read_file(*source);
    std::string error;
    mdp::ParameterStore(bench_dir("read"))
        .save(le::get32(&file[12]), Bytes(file.begin() + 20, file.end() - 4), error);
  }
  auto d = preop_device("read");  // serves the stored file (not the defaults)
  Bytes req, reply;
  for (auto _ : state) {
    size_t n = send(*d, foe::OpCode::ReadRequest, kPassword, kName, req, reply);
    while (n == 0) {  // deferred: the worker reads the file meanwhile (not timed)
      state.PauseTiming();
      std::this_thread::sleep_for(std::chrono::microseconds(50));
      state.ResumeTiming();
      reply.resize(kMailboxData);
      n = d->foe_poll(reply);
    }
    for (uint32_t packet = 1;; ++packet) {
      const bool last = n < kMailboxData;
      n = send(*d, foe::OpCode::Ack, packet, {}, req, reply);
      if (last) break;
    }
  }
}
BENCHMARK(BM_ParameterFoeReadDeviceThread)->Unit(benchmark::kMicrosecond);

void BM_ParameterFileSave(benchmark::State& state) {
  auto d = preop_device("save-source");
  const Bytes file = read_file(*d);
  const uint32_t fingerprint = le::get32(&file[12]);
  const Bytes payload(file.begin() + 20, file.end() - 4);
  mdp::ParameterStore store(bench_dir("save"));
  std::string error;
  for (auto _ : state) {
    if (!store.save(fingerprint, payload, error)) state.SkipWithError(error.c_str());
  }
}
BENCHMARK(BM_ParameterFileSave)->Unit(benchmark::kMicrosecond);

void BM_ParameterFileLoad(benchmark::State& state) {
  auto d = preop_device("load-source");
  const Bytes file = read_file(*d);
  const uint32_t fingerprint = le::get32(&file[12]);
  const Bytes payload(file.begin() + 20, file.end() - 4);
  mdp::ParameterStore store(bench_dir("load"));
  std::string error;
  store.save(fingerprint, payload, error);
  Bytes out;
  for (auto _ : state) {
    out.clear();
    std::string detail;
    benchmark::DoNotOptimize(store.load(fingerprint, out, detail));
  }
}
BENCHMARK(BM_ParameterFileLoad)->Unit(benchmark::kMicrosecond);

}  // namespace
