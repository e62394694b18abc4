// Where each process-data entry sits in the master's image: walks the PDO assignment
// (0x1C12 RxPDOs -> SM2 outputs, 0x1C13 TxPDOs -> SM3 inputs; ETG.1000.6 §5.6.7.4) and each
// assigned PDO's mapping (0x16xx / 0x1Axx: index << 16 | subindex << 8 | bit length,
// ETG.1000.6 §5.6.7.4.7) in order, as a master lays them out (ETG.2010 process data image).
// Offsets are relative to the slave's own output or input area; with one slave, SOEM (pysoem)
// places the outputs at byte 0 of its IOmap and the inputs right after all outputs.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "coe/object_dictionary.hpp"

namespace rackcat::apps {

struct PdoLayoutEntry {
  bool output = false;  // RxPDO (master -> slave) or TxPDO
  uint16_t pdo = 0;     // 0x16xx / 0x1Axx
  uint16_t index = 0;   // mapped object; 0 with subindex 0 is padding
  uint8_t subindex = 0;
  uint8_t bits = 0;
  uint32_t bit_offset = 0;  // from the start of the slave's output or input area
  std::string name;         // object name / entry name, "padding"
};

struct PdoLayout {
  std::vector<PdoLayoutEntry> entries;
  uint32_t output_bits = 0;
  uint32_t input_bits = 0;
};

// The layout of the current PDO assignment of `od`.
PdoLayout pdo_layout(const coe::ObjectDictionary& od);

}  // namespace rackcat::apps
