// The device's share of a cycle (no slot-card drivers attached: those are modules/'s): SM2 into
// the mapped objects plus the mapped objects into SM3 for the default rack, and the start-up
// costs (rack parsing, dictionary build) and one SDO upload through the mailbox.
#include <benchmark/benchmark.h>

#include <vector>

#include "mdp/device.hpp"
#include "mdp/object_dictionary_builder.hpp"

namespace {

using namespace rackcat;

mdp::DeviceOptions options() {
  mdp::DeviceOptions o;
  o.load_stored_parameters = false;
  o.state_dir = "/tmp/rackcat-bench-mdp";
  return o;
}

void BM_DefaultRackCycle(benchmark::State& state) {
  mdp::Device device(mdp::default_rack(), options());
  std::vector<uint8_t> sm2(device.output_bytes(), 0x55);
  std::vector<uint8_t> sm3(device.input_bytes());
  for (auto _ : state) {
    device.write_outputs(sm2);
    device.read_inputs(sm3);
    benchmark::DoNotOptimize(sm3.data());
  }
  state.counters["out_bytes"] = static_cast<double>(sm2.size());
  state.counters["in_bytes"] = static_cast<double>(sm3.size());
}
BENCHMARK(BM_DefaultRackCycle);

void BM_ParseDefaultRack(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(mdp::default_rack());
}
BENCHMARK(BM_ParseDefaultRack)->Unit(benchmark::kMicrosecond);

void BM_BuildDictionary(benchmark::State& state) {
  const mdp::RackConfig cfg = mdp::default_rack();
  for (auto _ : state) {
    coe::ObjectDictionary od;
    mdp::build_object_dictionary(cfg, od);
    benchmark::DoNotOptimize(od.size());
  }
}
BENCHMARK(BM_BuildDictionary)->Unit(benchmark::kMillisecond);

void BM_SdoUploadExpedited(benchmark::State& state) {
  mdp::Device device(mdp::default_rack(), options());
  device.state_changed(EsmState::Init, EsmState::PreOp);
  // ETG.1000.6 upload initiate of 0x1018:01, the mailbox data the firmware hands the CoE:
  // CoE header (service 2), SDO.
  const std::vector<uint8_t> req = {0x00, 0x20, 0x40, 0x18, 0x10, 0x01, 0, 0, 0, 0};
  std::vector<uint8_t> reply(122);
  size_t len = 0;
  for (auto _ : state) {
    len = device.coe_request(req, reply).length;
    benchmark::DoNotOptimize(len);
  }
  // 10 = an expedited upload response (0x43 + 4 bytes), not an abort or a mailbox error.
  state.counters["reply_len"] = static_cast<double>(len);
  state.counters["reply_cmd"] = reply[2];
}
BENCHMARK(BM_SdoUploadExpedited);

}  // namespace

BENCHMARK_MAIN();
