// AL status codes (ETG.1000.6 Table 11, extended by ETG.1020), the values the ESC writes to
// register 0x0134 together with the error flag 0x10 in AL status 0x0130.
#pragma once

#include <cstdint>
#include <string_view>

namespace rackcat::ecat {

namespace al_code {
inline constexpr uint16_t kNoError = 0x0000;
inline constexpr uint16_t kUnspecified = 0x0001;
inline constexpr uint16_t kInvalidStateChange = 0x0011;
inline constexpr uint16_t kUnknownState = 0x0012;
inline constexpr uint16_t kBootstrapNotSupported = 0x0013;
inline constexpr uint16_t kInvalidBootMailboxConfig = 0x0015;
inline constexpr uint16_t kInvalidMailboxConfig = 0x0016;
inline constexpr uint16_t kInvalidSmConfig = 0x0017;
inline constexpr uint16_t kSmWatchdog = 0x001B;
inline constexpr uint16_t kInvalidOutputConfig = 0x001D;
inline constexpr uint16_t kInvalidInputConfig = 0x001E;
inline constexpr uint16_t kFatalSyncError = 0x002C;
inline constexpr uint16_t kInvalidDcSyncConfig = 0x0030;
}  // namespace al_code

// The name ETG.1000.6 Table 11 gives a code ("Invalid requested state change"), or
// "Unknown AL status code" for values not in the table.
std::string_view al_status_code_name(uint16_t code);

}  // namespace rackcat::ecat
