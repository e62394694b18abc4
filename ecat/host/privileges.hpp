// Giving up root once the raw socket is open.
//
// A raw AF_PACKET socket needs CAP_NET_RAW to be opened, not to be used: after the link is
// up the process keeps no capability at all. drop_privileges() clears the effective,
// permitted, inheritable and ambient sets, empties the bounding set when it may (so no later
// execve can regain anything), sets no_new_privs, and optionally switches to an unprivileged
// user (explicit --user, or the user who ran sudo).
#pragma once

#include <sys/types.h>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>

namespace rackcat::ecat {

class PrivilegeError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct PrivilegeDropOptions {
  // User name or numeric uid to become. Empty: when running as root under sudo, the user
  // named by SUDO_UID/SUDO_GID; otherwise keep the current uid.
  std::string user;
  // Whether an empty `user` may fall back to SUDO_UID.
  bool use_sudo_user = true;
};

struct PrivilegeDropResult {
  uid_t uid = 0;
  gid_t gid = 0;
  bool switched_user = false;
};

// Throws PrivilegeError (with the reason) when a requested step fails: the caller should
// stop rather than run with more privilege than it asked to keep. Capabilities, the bounding
// set and no_new_privs are per thread, so the drop must happen before the process starts any
// thread: it throws (changing nothing) when /proc/self/task shows more than one. Every thread
// started afterwards inherits the dropped state.
PrivilegeDropResult drop_privileges(const PrivilegeDropOptions& options = {});

// The capability sets of this process as /proc/self/status reports them (CapEff etc.).
struct CapabilitySets {
  uint64_t effective = 0;
  uint64_t permitted = 0;
  uint64_t inheritable = 0;
  uint64_t bounding = 0;
  uint64_t ambient = 0;
};
std::optional<CapabilitySets> read_capability_sets();

}  // namespace rackcat::ecat
