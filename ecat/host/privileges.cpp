#include "ecat/host/privileges.hpp"

#include <dirent.h>
#include <grp.h>
#include <linux/capability.h>
#include <pwd.h>
#include <sys/prctl.h>
#include <sys/syscall.h>
#include <unistd.h>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <vector>

namespace rackcat::ecat {
namespace {

[[noreturn]] void fail(const std::string& step, int err) {
  throw PrivilegeError("cannot drop privileges: " + step + ": " + std::strerror(err));
}

int last_capability() {
  // The running kernel may know more capabilities than our headers.
  std::ifstream f("/proc/sys/kernel/cap_last_cap");
  int last = CAP_LAST_CAP;
  if (f) f >> last;
  return last;
}

bool parse_id(const char* s, unsigned long& out) {
  if (s == nullptr || *s == '\0') return false;
  char* end = nullptr;
  errno = 0;
  out = std::strtoul(s, &end, 10);
  return errno == 0 && end != nullptr && *end == '\0';
}

// Resolves a user name or numeric uid to (uid, primary gid).
bool lookup_user(const std::string& user, uid_t& uid, gid_t& gid) {
  std::vector<char> buf(16384);
  passwd pw{};
  passwd* found = nullptr;
  unsigned long numeric = 0;
  if (parse_id(user.c_str(), numeric)) {
    if (getpwuid_r(static_cast<uid_t>(numeric), &pw, buf.data(), buf.size(), &found) == 0 &&
        found != nullptr) {
      uid = found->pw_uid;
      gid = found->pw_gid;
    } else {
      // A uid without a passwd entry (containers): its own number as the group.
      uid = static_cast<uid_t>(numeric);
      gid = static_cast<gid_t>(numeric);
    }
    return true;
  }
  if (getpwnam_r(user.c_str(), &pw, buf.data(), buf.size(), &found) != 0 || found == nullptr) {
    return false;
  }
  uid = found->pw_uid;
  gid = found->pw_gid;
  return true;
}

void clear_capability_sets() {
  __user_cap_header_struct header{};
  header.version = _LINUX_CAPABILITY_VERSION_3;
  header.pid = 0;
  __user_cap_data_struct data[_LINUX_CAPABILITY_U32S_3]{};
  if (syscall(SYS_capset, &header, data) != 0) fail("capset", errno);
}

// Threads of this process (entries of /proc/self/task), or -1 when /proc cannot tell.
int thread_count() {
  DIR* d = ::opendir("/proc/self/task");
  if (d == nullptr) return -1;
  int n = 0;
  while (const dirent* e = ::readdir(d)) {
    if (e->d_name[0] != '.') ++n;
  }
  ::closedir(d);
  return n;
}

}  // namespace

PrivilegeDropResult drop_privileges(const PrivilegeDropOptions& options) {
  // capset(2), PR_CAPBSET_DROP and PR_SET_NO_NEW_PRIVS act on the calling thread only (and
  // glibc's setresuid covers all threads, the others do not): a thread started earlier would
  // keep every capability. The drop is therefore only done while this is the only thread.
  if (const int threads = thread_count(); threads != 1) {
    throw PrivilegeError(
        threads < 0 ? std::string("cannot drop privileges: /proc/self/task is not readable")
                    : "cannot drop privileges: " + std::to_string(threads) +
                          " threads are running and would keep their capabilities");
  }
  PrivilegeDropResult result;
  result.uid = getuid();
  result.gid = getgid();

  std::optional<std::pair<uid_t, gid_t>> target;
  if (!options.user.empty()) {
    uid_t uid = 0;
    gid_t gid = 0;
    if (!lookup_user(options.user, uid, gid)) {
      throw PrivilegeError("cannot drop privileges: no such user: " + options.user);
    }
    target = std::make_pair(uid, gid);
  } else if (options.use_sudo_user && geteuid() == 0) {
    unsigned long uid = 0;
    unsigned long gid = 0;
    if (parse_id(std::getenv("SUDO_UID"), uid) && uid != 0) {
      if (!parse_id(std::getenv("SUDO_GID"), gid)) gid = uid;
      target = std::make_pair(static_cast<uid_t>(uid), static_cast<gid_t>(gid));
    }
  }

  // Bounding set first, while CAP_SETPCAP is still effective. Without CAP_SETPCAP (started
  // with only CAP_NET_RAW) this is not possible, and no_new_privs below covers the same
  // ground: execve can then never add capabilities.
  const int last = last_capability();
  for (int cap = 0; cap <= last; ++cap) {
    if (prctl(PR_CAPBSET_DROP, cap, 0, 0, 0) != 0 && errno != EINVAL && errno != EPERM) {
      fail("PR_CAPBSET_DROP", errno);
    }
  }
  if (prctl(PR_CAP_AMBIENT, PR_CAP_AMBIENT_CLEAR_ALL, 0, 0, 0) != 0 && errno != EINVAL) {
    fail("PR_CAP_AMBIENT_CLEAR_ALL", errno);
  }

  if (target && (target->first != getuid() || target->second != getgid())) {
    // Groups, then gid, then uid: after setresuid we could no longer change the others.
    if (setgroups(1, &target->second) != 0) fail("setgroups", errno);
    if (setresgid(target->second, target->second, target->second) != 0) {
      fail("setresgid", errno);
    }
    if (setresuid(target->first, target->first, target->first) != 0) fail("setresuid", errno);
    result.uid = target->first;
    result.gid = target->second;
    result.switched_user = true;
  }

  clear_capability_sets();
  if (prctl(PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0) != 0) fail("PR_SET_NO_NEW_PRIVS", errno);

  // Trust, but verify: the kernel's view must show nothing left.
  const auto sets = read_capability_sets();
  if (!sets || sets->effective != 0 || sets->permitted != 0 || sets->ambient != 0) {
    throw PrivilegeError("cannot drop privileges: capabilities still present after capset");
  }
  return result;
}

std::optional<CapabilitySets> read_capability_sets() {
  std::ifstream f("/proc/self/status");
  if (!f) return std::nullopt;
  CapabilitySets sets;
  int found = 0;
  std::string line;
  while (std::getline(f, line)) {
    auto value = [&](const char* key, uint64_t& out) {
      const size_t n = std::strlen(key);
      if (line.compare(0, n, key) != 0) return;
      out = std::strtoull(line.c_str() + n, nullptr, 16);
      ++found;
    };
    value("CapInh:", sets.inheritable);
    value("CapPrm:", sets.permitted);
    value("CapEff:", sets.effective);
    value("CapBnd:", sets.bounding);
    value("CapAmb:", sets.ambient);
  }
  if (found < 4) return std::nullopt;  // CapAmb is missing on very old kernels
  return sets;
}

}  // namespace rackcat::ecat
