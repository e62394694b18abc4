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

Bytes message(uint8_t counter, uint8_t service, const Bytes& body) {
  Bytes m(8 + body.size());
  const uint16_t len = static_cast<uint16_t>(2 + body.size());
  m[0] = static_cast<uint8_t>(len);
  m[1] = static_cast<uint8_t>(len >> 8);
  m[5] = static_cast<uint8_t>(0x03 | (counter << 4));
  m[7] = static_cast<uint8_t>(service << 4);
  std::copy(body.begin(), body.end(), m.begin() + 8);
  return m;
}

// Seven copies with counters 1..7, as a master cycles them: no request is a repeat.
std::array<Bytes, 7> counted(uint8_t service, const Bytes& body) {
  std::array<Bytes, 7> out;
  for (uint8_t c = 1; c <= 7; ++c) out[c - 1] = message(c, service, body);
  return out;
}

void BM_ExpeditedUpload(benchmark::State& state) {
  ObjectDictionary od = test::make_test_dictionary();
  SdoServer server(od);
  const auto requests = counted(2, {0x40, 0x18, 0x10, 0x01, 0, 0, 0, 0});  // 0x1018:01
  std::array<uint8_t, 128> reply{};
  size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(server.handle(requests[i], reply, EsmState::Op));
    i = i == 6 ? 0 : i + 1;
  }
  if (reply[8] != 0x43) state.SkipWithError("unexpected reply");
}
BENCHMARK(BM_ExpeditedUpload);

void BM_ExpeditedDownload(benchmark::State& state) {
  ObjectDictionary od = test::make_test_dictionary();
  SdoServer server(od);
  const auto requests = counted(2, {0x2F, 0x00, 0x20, 0x00, 0x05, 0, 0, 0});  // 0x2000 = 5
  std::array<uint8_t, 128> reply{};
  size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(server.handle(requests[i], reply, EsmState::PreOp));
    i = i == 6 ? 0 : i + 1;
  }
  if (reply[8] != 0x60) state.SkipWithError("unexpected reply");
}
BENCHMARK(BM_ExpeditedDownload);

// A whole 255-byte segmented upload through a 128-byte mailbox: initiate + 2 segments.
void BM_SegmentedUpload255(benchmark::State& state) {
  ObjectDictionary od = test::make_test_dictionary();
  SdoServer server(od);
  std::array<Bytes, 3> steps{message(0, 2, {0x40, 0x02, 0x20, 0x00, 0, 0, 0, 0}),
                             message(0, 2, {0x60, 0, 0, 0, 0, 0, 0, 0}),
                             message(0, 2, {0x70, 0, 0, 0, 0, 0, 0, 0})};
  std::array<uint8_t, 128> reply{};
  for (auto _ : state) {
    for (const Bytes& s : steps) benchmark::DoNotOptimize(server.handle(s, reply, EsmState::Op));
  }
  if (reply[8] != 0x11) state.SkipWithError("unexpected reply");
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
  const Bytes request = message(0, 8, {0x01, 0x00, 0x00, 0x00, 0x01, 0x00});
  std::vector<uint8_t> reply(static_cast<size_t>(state.range(0)));
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
