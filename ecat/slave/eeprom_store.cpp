// The firmware stores its EEPROM content through the ESC's SII EEPROM interface from the PDI
// side (ESC datasheet 0x0500-0x050F; ETG.1000.4 §6.4.5 "SII EEPROM interface"), as a
// microcontroller does after a firmware update: the identity words (ETG.2010 Table 2, e.g.
// 0x0C revision) and categories the master reads must describe the firmware that runs.
//
// Sequence: the master offers the EEPROM to the PDI (0x0500 bit 0, SOEM does so at the end of
// its scan); the PDI takes it (0x0501 bit 0 = 1), reads the chip word by word (command 001b,
// 4 or 8 bytes a read, 0x0502 bit 6), writes each word that differs (data 0x0508, address
// 0x0504, command 010b with write enable bit 0), erases what lies past the new image, reloads
// the configuration area (command 100b) if words 0-7 changed, and gives the EEPROM back.
#include <algorithm>
#include <array>
#include <span>

#include "base/little_endian.hpp"
#include "ecat/registers.hpp"
#include "ecat/slave/firmware.hpp"

namespace rackcat::ecat {

namespace {

// 0x0502-0x0503 bits (ESC datasheet 0x0502).
constexpr uint16_t kReadSize8 = 0x0040;
constexpr uint16_t kCommandErrors = 0x6000;  // NACK, write enable error
constexpr uint16_t kCmdRead = 0x0100;
constexpr uint16_t kCmdWrite = 0x0201;  // write with write enable
constexpr uint16_t kCmdReload = 0x0400;
constexpr uint8_t kPdiTakes = 0x01;

uint16_t image_word(std::span<const uint8_t> image, uint32_t word) {
  const size_t at = static_cast<size_t>(word) * 2;
  if (at + 1 < image.size()) return le::get16(&image[at]);
  if (at < image.size()) return static_cast<uint16_t>(image[at] | 0xFF00);
  return 0xFFFF;  // erased
}

}  // namespace

bool Firmware::store_eeprom() {
  eeprom_pending_ = true;
  if ((pdi_.read8(reg::kSiiConfig) & 0x01) == 0) return false;  // the master holds it
  pdi_.write8(reg::kSiiPdiAccess, kPdiTakes);
  if ((pdi_.read8(reg::kSiiPdiAccess) & kPdiTakes) == 0) return false;
  eeprom_pending_ = false;

  const std::span<const uint8_t> image = app_.eeprom();
  auto command = [&](uint16_t cmd, uint32_t word) {
    pdi_.write32(reg::kSiiAddress, word);
    pdi_.write16(reg::kSiiControl, cmd);
    return (pdi_.read16(reg::kSiiControl) & kCommandErrors) == 0;
  };
  const uint32_t words_per_read = (pdi_.read16(reg::kSiiControl) & kReadSize8) ? 4 : 2;
  const auto image_words = static_cast<uint32_t>((image.size() + 1) / 2);
  bool config_area_changed = false;
  // An image larger than the chip is refused before anything is written.
  bool ok = image_words == 0 || command(kCmdRead, image_words - 1);
  uint32_t word = 0;
  // Word by word until the chip ends (a read past it is NACKed).
  for (; ok && command(kCmdRead, word); word += words_per_read) {
    std::array<uint8_t, 8> chip{};
    pdi_.read(reg::kSiiData, std::span<uint8_t>(chip.data(), words_per_read * 2));
    for (uint32_t i = 0; ok && i < words_per_read; ++i) {
      const uint16_t want = image_word(image, word + i);
      if (le::get16(&chip[i * 2]) == want) continue;
      pdi_.write16(reg::kSiiData, want);
      // A word past the chip's end (the last read's tail) is NACKed: only the image matters.
      ok = command(kCmdWrite, word + i) || word + i >= image_words;
      if (word + i < 8) config_area_changed = true;
    }
  }
  if (ok && config_area_changed) ok = command(kCmdReload, 0);
  pdi_.write8(reg::kSiiPdiAccess, 0);  // back to the master
  return ok;
}

}  // namespace rackcat::ecat
