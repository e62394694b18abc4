// Per-state access rights of an object entry, encoded exactly as the ObjectAccess word of an
// SDO Information entry description (ETG.1000.6 §5.6.3.6.2, Table 46), so the same bits serve
// the SDO server, SDO Information and the ESI generator.
#pragma once

#include <cstdint>
#include <optional>
#include <string_view>

#include "base/esm_state.hpp"

namespace rackcat::coe {

namespace access {
inline constexpr uint16_t kReadPreOp = 0x0001;
inline constexpr uint16_t kReadSafeOp = 0x0002;
inline constexpr uint16_t kReadOp = 0x0004;
inline constexpr uint16_t kWritePreOp = 0x0008;
inline constexpr uint16_t kWriteSafeOp = 0x0010;
inline constexpr uint16_t kWriteOp = 0x0020;
inline constexpr uint16_t kRxPdoMappable = 0x0040;
inline constexpr uint16_t kTxPdoMappable = 0x0080;
inline constexpr uint16_t kBackup = 0x0100;
inline constexpr uint16_t kSettings = 0x0200;

inline constexpr uint16_t kReadAll = kReadPreOp | kReadSafeOp | kReadOp;
inline constexpr uint16_t kWriteAll = kWritePreOp | kWriteSafeOp | kWriteOp;

// The Fusion.IO guide's access column (Appendix A, Table 24):
//   "ro"          -> read in every state, never written           (kRo)
//   "rw"          -> read and write in every state                 (kRw)
//   "ro,wr_preop" -> read in every state, write only in PREOP      (kRoWrPreOp)
//   "ro,wr_op"    -> read in every state, write only in OP         (kRoWrOp)
//   "wo"          -> write in every state, never read              (kWo)
inline constexpr uint16_t kRo = kReadAll;
inline constexpr uint16_t kRw = kReadAll | kWriteAll;
inline constexpr uint16_t kRoWrPreOp = kReadAll | kWritePreOp;
inline constexpr uint16_t kRoWrOp = kReadAll | kWriteOp;
inline constexpr uint16_t kWo = kWriteAll;

// Parses the guide's notation ("ro", "rw", "ro,wr_preop", "ro,wr_op", "wo"); nullopt otherwise.
std::optional<uint16_t> from_guide(std::string_view text);
// The guide's notation for the read/write bits of `bits` (PDO/backup/settings flags ignored);
// empty when the combination has no guide spelling (e.g. written in SAFEOP only).
std::string_view to_guide(uint16_t bits);
bool can_read(uint16_t bits, EsmState s);
bool can_write(uint16_t bits, EsmState s);
}  // namespace access

}  // namespace rackcat::coe
