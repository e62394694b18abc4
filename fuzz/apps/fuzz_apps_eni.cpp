// libFuzzer target of the ENI reader (apps/line/eni_file.hpp): any text must either build a
// line (every device from the test ESI directory) or be refused with device::FileError
// ("FILE:LINE: reason" naming the ENI or the ESI). Any other exception, a crash, a hang or a
// sanitizer report is a bug. A line that is accepted is also built into its devices.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "apps/line/eni_file.hpp"
#include "device/esi_error.hpp"
#include "device/generic_device.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  rackcat::apps::LineFile line;
  try {
    line = rackcat::apps::parse_eni_file(text, "fuzz.eni.xml", RACKCAT_DEVICE_TEST_DATA);
  } catch (const rackcat::device::FileError& e) {
    if (e.file().empty()) std::abort();
    return 0;
  }
  for (auto& d : line.devices) {
    if (!d.esi) continue;
    const rackcat::device::GenericDevice device(std::move(*d.esi));
    (void)device.process_data_sizes();
  }
  return 0;
}
