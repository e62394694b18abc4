// ESI and SII generation time for large racks (issue target: < 200 ms for 255 modules).
//
// A rack file holds at most 5 RIMs x 24 slots = 120 modules (docs/MDP.md), so the 255-module
// case uses a dictionary assembled from mdp's own objects: the default rack's device objects
// plus 255 modules cycling through the catalogue's module types, each module's objects and
// mapping objects moved to its ETG.5001 indices (0xAnnX, 0x1600/0x1A00 + n - 1) and all PDOs
// assigned in 0x1C12/0x1C13.
#include <benchmark/benchmark.h>

#include <string>

#include "esi/describe_dictionary.hpp"
#include "esi/esi_writer.hpp"
#include "esi/rack.hpp"
#include "mdp/device.hpp"
#include "mdp/rack_config.hpp"
#include "mdp/sync_manager_layout.hpp"
#include "tests/esi/rack_files.hpp"

namespace rackcat::esi {
namespace {

mdp::DeviceOptions no_state() {
  mdp::DeviceOptions o;
  o.load_stored_parameters = false;
  return o;
}

bool is_module_object(uint16_t index) {
  return index >= 0x3001 && index <= 0x7FFF;
}

coe::Object moved(const coe::Object& src, uint16_t index) {
  coe::Object o(index, src.code(), src.name(), src.data_type());
  o.set_packed(src.packed());
  for (const auto& e : src.entries()) o.add(e);
  o.finalize();
  for (size_t i = 0; i < o.image().size(); ++i) o.image()[i] = src.image()[i];
  return o;
}

coe::Object assignment(uint16_t index, const std::vector<uint16_t>& pdos) {
  coe::Object o(index, coe::ObjectCode::Array, "PDO assignment", 0x0006);
  coe::Entry sub0;
  sub0.name = "SubIndex 000";
  sub0.data_type = 0x0005;
  sub0.access = coe::access::kRoWrPreOp;
  sub0.default_value = {static_cast<uint8_t>(pdos.size())};
  o.add(sub0);
  for (size_t i = 0; i < pdos.size(); ++i) {
    coe::Entry e;
    e.subindex = static_cast<uint8_t>(i + 1);
    e.name = "SubIndex " + std::to_string(i + 1);
    e.data_type = 0x0006;
    e.access = coe::access::kRoWrPreOp;
    e.default_value = {static_cast<uint8_t>(pdos[i]), static_cast<uint8_t>(pdos[i] >> 8)};
    o.add(e);
  }
  return o;
}

struct Rack255 {
  std::unique_ptr<mdp::Device> base =
      std::make_unique<mdp::Device>(mdp::default_rack(), no_state());
  std::unique_ptr<mdp::Device> catalogue = std::make_unique<mdp::Device>(
      mdp::parse_rack_config(catalogue_rack_yaml(), "<catalogue>"), no_state());
  coe::ObjectDictionary od;

  Rack255() {
    // Device-level objects of the default rack (no module objects, no PDOs).
    base->dictionary().for_each([&](const coe::Object& o) {
      uint16_t i = o.index();
      if (is_module_object(i) || (i >= 0x1600 && i <= 0x1BFF) || i == 0x1C12 || i == 0x1C13) return;
      od.add(moved(o, i));
    });
    for (const auto& [index, en] : catalogue->dictionary().enums()) od.add_enum(en);
    const auto& cat = catalogue->dictionary();
    auto types = catalogue->modules();
    std::vector<uint16_t> rx, tx;
    for (uint16_t n = 1; n <= 255; ++n) {
      const auto& m = types[(n - 1) % types.size()];
      const int shift = (n - 1 - m.nn()) * 0x10;
      cat.for_each([&](const coe::Object& o) {
        if (!is_module_object(o.index()) || ((o.index() >> 4) & 0xFF) != m.nn() ||
            (o.index() < 0x4000 && (o.index() & 0xF) == 0))
          return;
        od.add(moved(o, static_cast<uint16_t>(o.index() + shift)));
      });
      auto map = [&](uint16_t from, uint16_t to, std::vector<uint16_t>& list) {
        const auto* src = cat.find(from);
        if (!src) return;
        auto o = moved(*src, to);
        for (uint8_t s = 1; s <= o.sub0(); ++s) {
          uint64_t v = o.get_u(s);
          if (v >> 16) o.set_u(s, v + (static_cast<uint64_t>(shift) << 16));
        }
        od.add(std::move(o));
        list.push_back(to);
      };
      map(mdp::sm::rx_pdo_index(m.number), mdp::sm::rx_pdo_index(n), rx);
      map(mdp::sm::tx_pdo_index(m.number), mdp::sm::tx_pdo_index(n), tx);
    }
    od.add(assignment(0x1C12, rx));
    od.add(assignment(0x1C13, tx));
  }
};

void BM_SiiAndEsi255Modules(benchmark::State& state) {
  Rack255 rack;
  DeviceTexts texts{"rackcat", "FI-CM0100-00", "FusionIO", "Fusion.IO-style modular I/O racks"};
  size_t bytes = 0;
  for (auto _ : state) {
    auto d = describe_dictionary(rack.od, texts, SmPlan{});
    auto sii = encode_sii(d);
    EsiContent c;
    c.device = &d;
    c.dictionary = &rack.od;
    c.config_data = encode_config_area(d.config);
    c.eeprom_bytes = sii.bytes.size();
    c.modules = describe_module_types();
    auto xml = write_esi(c);
    bytes = xml.size() + sii.bytes.size();
    benchmark::DoNotOptimize(xml.data());
  }
  state.counters["objects"] = static_cast<double>(rack.od.size());
  state.counters["output_bytes"] = static_cast<double>(bytes);
}
BENCHMARK(BM_SiiAndEsi255Modules)->Unit(benchmark::kMillisecond);

void BM_SiiAndEsi120ModuleRackFile(benchmark::State& state) {
  mdp::Device device(mdp::parse_rack_config(testing::rack_120_yaml(), "<120 modules>"), no_state());
  for (auto _ : state) {
    auto sii = build_sii(device);
    auto xml = write_esi(device);
    benchmark::DoNotOptimize(sii.bytes.data());
    benchmark::DoNotOptimize(xml.data());
  }
  state.counters["objects"] = static_cast<double>(device.dictionary().size());
}
BENCHMARK(BM_SiiAndEsi120ModuleRackFile)->Unit(benchmark::kMillisecond);

void BM_SiiOnly120ModuleRackFile(benchmark::State& state) {
  mdp::Device device(mdp::parse_rack_config(testing::rack_120_yaml(), "<120 modules>"), no_state());
  for (auto _ : state) {
    auto sii = build_sii(device);
    benchmark::DoNotOptimize(sii.bytes.data());
  }
}
BENCHMARK(BM_SiiOnly120ModuleRackFile)->Unit(benchmark::kMillisecond);

// The ETG.5001 module descriptions (a catalogue device built by mdp): part of every ESI.
void BM_DescribeModuleTypes(benchmark::State& state) {
  for (auto _ : state) {
    auto modules = describe_module_types();
    benchmark::DoNotOptimize(modules.data());
  }
}
BENCHMARK(BM_DescribeModuleTypes)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace rackcat::esi

BENCHMARK_MAIN();
