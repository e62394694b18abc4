// Per-state access (ETG.1000.6 §5.6.3.6.2 Table 46 ObjectAccess bits) and the Fusion.IO
// guide's access notation (Appendix A, Table 24).
#include "coe/access.hpp"

#include <array>

namespace rackcat::coe::access {
namespace {

struct GuideAccess {
  std::string_view text;
  uint16_t bits;
};
constexpr std::array<GuideAccess, 5> kGuide{{
    {"ro", kRo},
    {"rw", kRw},
    {"ro,wr_preop", kRoWrPreOp},
    {"ro,wr_op", kRoWrOp},
    {"wo", kWo},
}};

// The bit for a state; INIT and BOOT have no SDO access (the mailbox of INIT carries no CoE,
// BOOT only FoE: ETG.1000.6 §5.3), so they map to no bit.
uint16_t state_bit(uint16_t read_bit, EsmState s) {
  switch (s) {
    case EsmState::PreOp:
      return read_bit;
    case EsmState::SafeOp:
      return static_cast<uint16_t>(read_bit << 1);
    case EsmState::Op:
      return static_cast<uint16_t>(read_bit << 2);
    default:
      return 0;
  }
}

}  // namespace

std::optional<uint16_t> from_guide(std::string_view text) {
  // The guide writes both "ro,wr_preop" and "ro, wr_preop" and upper case "RO"/"RW".
  char buf[32];
  size_t n = 0;
  for (char c : text) {
    if (c == ' ' || c == '\t') {
      continue;
    }
    if (n == sizeof buf) {
      return std::nullopt;
    }
    buf[n++] = (c >= 'A' && c <= 'Z') ? static_cast<char>(c - 'A' + 'a') : c;
  }
  const std::string_view norm(buf, n);
  for (const auto& g : kGuide) {
    if (g.text == norm) {
      return g.bits;
    }
  }
  return std::nullopt;
}

std::string_view to_guide(uint16_t bits) {
  const uint16_t rw = bits & (kReadAll | kWriteAll);
  for (const auto& g : kGuide) {
    if (g.bits == rw) {
      return g.text;
    }
  }
  return {};
}

bool can_read(uint16_t bits, EsmState s) {
  return (bits & state_bit(kReadPreOp, s)) != 0;
}
bool can_write(uint16_t bits, EsmState s) {
  return (bits & state_bit(kWritePreOp, s)) != 0;
}

}  // namespace rackcat::coe::access
