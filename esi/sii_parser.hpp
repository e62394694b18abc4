// Reads an SII EEPROM image back into its parts (ETG.2010), as a master does: the header words,
// the configuration-area CRC, then the category walk from word 0x40 up to the End marker.
// Used by the tests, by `rackcat sii --dump` and by the fuzzer; never trusts the input.
#pragma once

#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "esi/device_description.hpp"

namespace rackcat::esi {

class SiiParseError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct SiiGeneral {
  uint8_t group_idx = 0, image_idx = 0, order_idx = 0, name_idx = 0;
  uint8_t coe_details = 0, foe_details = 0, eoe_details = 0, soe_channels = 0, ds402_channels = 0;
  uint8_t sysman_class = 0, flags = 0;
  int16_t ebus_current_ma = 0;
  uint16_t physical_ports = 0;
  uint16_t physical_memory_address = 0;
};

struct SiiSyncManager {
  uint16_t start = 0, length = 0;
  uint8_t control = 0, status = 0, enable = 0, type = 0;
};

struct SiiPdoEntry {
  uint16_t index = 0;
  uint8_t subindex = 0, name_idx = 0, data_type = 0, bit_length = 0;
  uint16_t flags = 0;
};

struct SiiPdo {
  uint16_t index = 0;
  uint8_t sm = 0, synchronization = 0, name_idx = 0;
  uint16_t flags = 0;
  std::vector<SiiPdoEntry> entries;
};

struct SiiDcMode {
  uint32_t cycle_time_sync0 = 0;
  int32_t shift_time_sync0 = 0, shift_time_sync1 = 0;
  int16_t cycle_time_sync1_factor = 0;
  uint16_t assign_activate = 0;
  int16_t cycle_time_sync0_factor = 0;
  uint8_t name_idx = 0, description_idx = 0;
};

struct SiiCategoryHeader {
  uint16_t type = 0;
  uint16_t word_address = 0;  // of the header
  uint16_t length_words = 0;
};

struct SiiInfo {
  uint16_t pdi_control = 0, pdi_config = 0, sync_impulse_length = 0, extended_pdi_config = 0;
  uint16_t station_alias = 0;
  uint8_t checksum = 0;
  uint32_t vendor_id = 0, product_code = 0, revision = 0, serial = 0;
  uint16_t bootstrap_receive_offset = 0, bootstrap_receive_size = 0;
  uint16_t bootstrap_send_offset = 0, bootstrap_send_size = 0;
  uint16_t standard_receive_offset = 0, standard_receive_size = 0;
  uint16_t standard_send_offset = 0, standard_send_size = 0;
  uint16_t mailbox_protocol = 0;
  uint16_t size_kbit_minus_one = 0;
  uint16_t version = 0;

  std::vector<SiiCategoryHeader> categories;  // in image order, End excluded
  std::vector<std::string> strings;           // strings[0] is index 1
  bool has_general = false;
  SiiGeneral general;
  std::vector<uint8_t> fmmus;
  std::vector<SiiSyncManager> sms;
  std::vector<SiiPdo> tx_pdos;
  std::vector<SiiPdo> rx_pdos;
  std::vector<SiiDcMode> dc_modes;

  // The string with SII index `idx` (1-based); "" for 0 or an index past the table.
  std::string string(uint8_t idx) const;
};

// Throws SiiParseError naming the word address and the problem: image too short, odd or over
// 128 KiB, configuration-area CRC mismatch, a category running past the end of the image, a
// malformed category body, or no End marker.
SiiInfo parse_sii(std::span<const uint8_t> image);

// Human-readable dump (for `rackcat sii --dump`).
std::string format_sii(const SiiInfo& info);

}  // namespace rackcat::esi
