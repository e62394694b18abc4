// SDO server and process image throughput, in-process (no ESC, no network).
#include <benchmark/benchmark.h>

#include <array>
#include <vector>

#include "coe/process_image.hpp"
#include "coe/sdo_server.hpp"
#include "tests/coe/test_dictionary.hpp"

namespace rackcat::coe {
namespace {

using Bytes = std::vector<uint8_t>;

// The CoE data of one mailbox message (CoE header + body): what the firmware's MailboxServer
// hands the SDO server once it has read the mailbox header.
Bytes message(uint8_t service, const Bytes& body) {
  Bytes m(2 + body.size());
  m[1] = static_cast<uint8_t>(service << 4);
  std::copy(body.begin(), body.end(), m.begin() + 2);
  return m;
}

void BM_ExpeditedUpload(benchmark::State& state) {
  ObjectDictionary od = test::make_test_dictionary();
  SdoServer server(od);
  const Bytes request = message(2, {0x40, 0x18, 0x10, 0x01, 0, 0, 0, 0});  // 0x1018:01
  std::array<uint8_t, 122> reply{};
  for (auto _ : state) {
    benchmark::DoNotOptimize(server.handle(request, reply, EsmState::Op));
  }
  if (reply[2] != 0x43) state.SkipWithError("unexpected reply");
}
BENCHMARK(BM_ExpeditedUpload);

void BM_ExpeditedDownload(benchmark::State& state) {
  ObjectDictionary od = test::make_test_dictionary();
  SdoServer server(od);
  const Bytes request = message(2, {0x2F, 0x00, 0x20, 0x00, 0x05, 0, 0, 0});  // 0x2000 = 5
  std::array<uint8_t, 122> reply{};
  for (auto _ : state) {
    benchmark::DoNotOptimize(server.handle(request, reply, EsmState::PreOp));
  }
  if (reply[2] != 0x60) state.SkipWithError("unexpected reply");
}
BENCHMARK(BM_ExpeditedDownload);

// A whole 255-byte segmented upload through a 128-byte mailbox: initiate + 2 segments.
void BM_SegmentedUpload255(benchmark::State& state) {
  ObjectDictionary od = test::make_test_dictionary();
  SdoServer server(od);
  std::array<Bytes, 3> steps{message(2, {0x40, 0x02, 0x20, 0x00, 0, 0, 0, 0}),
                             message(2, {0x60, 0, 0, 0, 0, 0, 0, 0}),
                             message(2, {0x70, 0, 0, 0, 0, 0, 0, 0})};
  std::array<uint8_t, 122> reply{};
  for (auto _ : state) {
    for (const Bytes& s : steps) benchmark::DoNotOptimize(server.handle(s, reply, EsmState::Op));
  }
  if (reply[2] != 0x11) state.SkipWithError("unexpected reply");
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations()) * 255);
}
BENCHMARK(BM_SegmentedUpload255);

// SDO Information OD list (all objects) of a 2,500-object dictionary: the request and every
// fragment, through a mailbox of `range(0)` bytes.
void BM_OdList2500(benchmark::State& state) {
  ObjectDictionary od;
  for (uint16_t i = 0; i < 2500; ++i)
    od.add(test::var(static_cast<uint16_t>(0x2000 + i), "Object", DataType::Unsigned16, 16,
                     access::kRw));
  SdoServer server(od);
  const Bytes request = message(8, {0x01, 0x00, 0x00, 0x00, 0x01, 0x00});
  std::vector<uint8_t> reply(static_cast<size_t>(state.range(0)) - 6);
  size_t fragments = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(server.handle(request, reply, EsmState::PreOp));
    ++fragments;
    while (server.poll(reply)) ++fragments;
  }
  state.counters["fragments"] =
      benchmark::Counter(static_cast<double>(fragments) / static_cast<double>(state.iterations()));
}
BENCHMARK(BM_OdList2500)->Arg(128)->Arg(1024);

void BM_Find2500(benchmark::State& state) {
  ObjectDictionary od;
  for (uint16_t i = 0; i < 2500; ++i)
    od.add(test::var(static_cast<uint16_t>(0x2000 + 3 * i), "Object", DataType::Unsigned8, 8,
                     access::kRw));
  uint16_t index = 0x2000;
  for (auto _ : state) {
    benchmark::DoNotOptimize(od.find(index));
    index = static_cast<uint16_t>(index >= 0x2000 + 3 * 2499 ? 0x2000 : index + 3);
  }
}
BENCHMARK(BM_Find2500);

// One cycle of the test dictionary's process image (3 output bytes, 3 input bytes).
void BM_ProcessImageCycle(benchmark::State& state) {
  ObjectDictionary od = test::make_test_dictionary();
  ProcessImage image(od);
  if (image.compile() != AbortCode::None) state.SkipWithError("compile failed");
  std::vector<uint8_t> sm2(image.output_bytes(), 0x11), sm3(image.input_bytes());
  for (auto _ : state) {
    image.write_outputs(sm2);
    image.read_inputs(sm3);
    benchmark::DoNotOptimize(sm3.data());
  }
}
BENCHMARK(BM_ProcessImageCycle);

}  // namespace
}  // namespace rackcat::coe

BENCHMARK_MAIN();
