// libFuzzer target of the line file reader (apps/line/line_file.hpp): any text must either
// build a line or be refused with device::FileError ("FILE:LINE: reason"). Files it names are
// read below tests/device/data only. Any other exception, a crash, a hang or a sanitizer report
// is a bug. An accepted line is built into its devices, wired and its signal sources sampled.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "apps/line/line_file.hpp"
#include "device/esi_error.hpp"
#include "device/generic_device.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  rackcat::apps::LineFile line;
  try {
    line = rackcat::apps::parse_line_file(text, RACKCAT_DEVICE_TEST_DATA "/fuzz-line.yaml");
  } catch (const rackcat::device::FileError& e) {
    if (e.file().empty()) std::abort();
    return 0;
  }
  std::vector<std::unique_ptr<rackcat::device::GenericDevice>> at(line.devices.size());
  for (size_t i = 0; i < line.devices.size(); ++i) {
    if (line.devices[i].esi)
      at[i] = std::make_unique<rackcat::device::GenericDevice>(std::move(*line.devices[i].esi));
  }
  for (size_t i = 0; i < line.devices.size(); ++i) {
    for (const auto& in : line.devices[i].inputs) {
      if (!at[i] || !in.source || in.bits == 0 || in.bits > 64) std::abort();
      at[i]->add_input_driver(in.bit, in.bits, [&in] { return in.code(in.source->sample(0.25)); });
    }
  }
  for (const auto& w : line.wiring) {
    if (!at[w.from] || !at[w.to]) std::abort();  // the reader wires ESI devices only
    at[w.to]->add_wire(*at[w.from], w.from_bit, w.to_bit, w.bits);
  }
  std::vector<uint8_t> inputs(4096);
  for (auto& d : at) {
    if (d) d->update_inputs(std::span<uint8_t>(inputs.data(), d->process_data_sizes().inputs));
  }
  return 0;
}
