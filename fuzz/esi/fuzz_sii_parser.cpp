// libFuzzer target for the SII parser: any byte string must parse or throw SiiParseError,
// never crash, hang or read out of bounds. When the first byte is odd the input's CRC word is
// fixed up first, so the fuzzer gets past the configuration-area check into the categories.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "esi/sii_crc.hpp"
#include "esi/sii_parser.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::vector<uint8_t> image(data, data + size);
  if (image.size() >= 16 && (image[0] & 1)) {
    image[14] = rackcat::esi::sii_crc8(std::span<const uint8_t>(image.data(), 14));
    image[15] = 0;
  }
  try {
    auto info = rackcat::esi::parse_sii(image);
    (void)rackcat::esi::format_sii(info);
  } catch (const rackcat::esi::SiiParseError&) {
  }
  return 0;
}
