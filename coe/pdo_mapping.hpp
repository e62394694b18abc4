// PDO assignment and mapping rules (ETG.1000.6 §5.6.7.4.7 - §5.6.7.4.9): 0x1C12 lists the
// RxPDO mapping objects (0x1600..0x17FF) whose entries go to the outputs (SM2), 0x1C13 the
// TxPDO mapping objects (0x1A00..0x1BFF) for the inputs (SM3). A mapping entry is
// index << 16 | subindex << 8 | bit length; index 0 (or a data type index below 0x1000, the
// CiA 301 dummy mapping) is padding.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <span>

#include "coe/abort_code.hpp"
#include "coe/object_dictionary.hpp"

namespace rackcat::coe {

enum class PdoDirection : uint8_t { Rx, Tx };  // Rx = outputs (master -> slave), Tx = inputs

inline constexpr uint16_t kRxPdoAssign = 0x1C12;
inline constexpr uint16_t kTxPdoAssign = 0x1C13;

struct MappingEntry {
  uint16_t index = 0;
  uint8_t subindex = 0;
  uint8_t bits = 0;
  static MappingEntry decode(uint32_t v) {
    return {static_cast<uint16_t>(v >> 16), static_cast<uint8_t>(v >> 8), static_cast<uint8_t>(v)};
  }
  bool is_padding() const { return index < 0x1000; }
};

// The mapping-object index range of a direction: 0x1600..0x17FF or 0x1A00..0x1BFF.
bool is_mapping_index(uint16_t index, PdoDirection dir);

// One mapping entry: 0x06020000 object unknown, 0x06090011 subindex unknown, 0x06040041 not
// mappable in this direction, 0x06040043 bit length differs from the entry's.
AbortCode check_mapping_entry(const ObjectDictionary& od, uint32_t value, PdoDirection dir,
                              const Entry** target = nullptr);
// Total bits a mapping object maps with its current content, or an abort code through `rc`.
size_t mapping_bits(const ObjectDictionary& od, const Object& mapping, PdoDirection dir,
                    AbortCode& rc);

using WriteValidator =
    std::function<AbortCode(const Object&, int, std::span<const uint8_t>, EsmState)>;

// validate_write hooks for a mapping object and an assign object. Both refuse a write of
// subindex n >= 1 while subindex 0 is not 0 (0x06010003), check every entry that would be in
// use, and refuse a configuration over `max_bytes` of process data (0x06040042). The assign
// validator refuses an index outside its mapping range (0x06040043) or a missing mapping object
// (0x06020000). `od` must outlive the hooks.
WriteValidator pdo_mapping_validator(const ObjectDictionary& od, PdoDirection dir,
                                     size_t max_bytes);
WriteValidator pdo_assign_validator(const ObjectDictionary& od, PdoDirection dir, size_t max_bytes);
// Installs the validators on 0x1C12, 0x1C13 and every mapping object present (replacing their
// validate_write hooks).
void install_pdo_validators(ObjectDictionary& od, size_t max_output_bytes, size_t max_input_bytes);

}  // namespace rackcat::coe
