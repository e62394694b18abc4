// drop_privileges(): once the raw socket is open the slave keeps no capability, and the open
// socket keeps working. Each test runs in a child process: dropping is irreversible.
#include <gtest/gtest.h>

#include <unistd.h>
#include <condition_variable>
#include <cstdlib>
#include <fstream>
#include <mutex>
#include <string>
#include <thread>

#include "ecat/host/privileges.hpp"
#include "ecat/host/raw_socket_link.hpp"
#include "tests/ecat/link_test_util.hpp"

namespace rackcat::ecat {
namespace {

// CapEff straight from /proc/self/status, as an administrator would check it.
uint64_t cap_eff_from_proc(const char* status = "/proc/self/status") {
  std::ifstream f(status);
  std::string line;
  while (std::getline(f, line)) {
    if (line.rfind("CapEff:", 0) == 0) return std::strtoull(line.c_str() + 7, nullptr, 16);
  }
  return ~0ull;
}

TEST(LinkPrivileges, AfterDropNoCapabilityRemainsAndTheSocketStillWorks) {
  if (!testutil::can_open_raw_socket()) GTEST_SKIP() << "needs root or CAP_NET_RAW";
  const int status = testutil::in_child([] {
    RawSocketLink link("lo");
    drop_privileges({.user = "", .use_sudo_user = false});
    if (cap_eff_from_proc() != 0) return 1;
    const auto sets = read_capability_sets();
    if (!sets || sets->permitted != 0 || sets->inheritable != 0 || sets->ambient != 0) return 2;
    if (getuid() == 0 && sets->bounding != 0) return 3;  // root could drop the bounding set
    // The socket opened before the drop sends and receives.
    const auto frame = testutil::ethercat_frame(0x44);
    if (!link.send(frame)) return 4;
    const auto got = testutil::receive_matching(link, [](std::span<const uint8_t> f) {
      return f.size() > testutil::kFirstDataByte && f[testutil::kFirstDataByte] == 0x44;
    });
    return got == frame ? 0 : 5;
  });
  EXPECT_EQ(status, 0);
}

TEST(LinkPrivileges, SwitchesToTheNamedUser) {
  if (getuid() != 0) GTEST_SKIP() << "needs root";
  const int status = testutil::in_child([] {
    const auto r = drop_privileges({.user = "65534", .use_sudo_user = false});
    if (!r.switched_user || getuid() != 65534 || geteuid() != 65534) return 1;
    return cap_eff_from_proc() == 0 ? 0 : 2;
  });
  EXPECT_EQ(status, 0);
}

TEST(LinkPrivileges, SwitchesToTheSudoUser) {
  if (getuid() != 0) GTEST_SKIP() << "needs root";
  const int status = testutil::in_child([] {
    setenv("SUDO_UID", "65533", 1);
    setenv("SUDO_GID", "65533", 1);
    const auto r = drop_privileges();
    if (!r.switched_user || getuid() != 65533 || getgid() != 65533) return 1;
    return cap_eff_from_proc() == 0 ? 0 : 2;
  });
  EXPECT_EQ(status, 0);
}

TEST(LinkPrivileges, UnknownUserIsAnErrorAndNothingChanges) {
  const int status = testutil::in_child([] {
    const uid_t before = getuid();
    try {
      drop_privileges({.user = "rackcat-no-such-user", .use_sudo_user = false});
    } catch (const PrivilegeError& e) {
      if (std::string(e.what()).find("rackcat-no-such-user") == std::string::npos) return 2;
      return getuid() == before ? 0 : 3;
    }
    return 1;
  });
  EXPECT_EQ(status, 0);
}

}  // namespace
}  // namespace rackcat::ecat

namespace rackcat::ecat {
namespace {

// Issue 14 item 5: capset and the bounding-set drop act per thread; a thread started before
// the drop kept every capability. The drop now refuses to run beside another thread.
TEST(LinkPrivileges, RefusesToDropWhileAnotherThreadRuns) {
  const int status = testutil::in_child([] {
    std::mutex m;
    std::condition_variable cv;
    bool done = false;
    std::thread other([&] {
      std::unique_lock lock(m);
      cv.wait(lock, [&] { return done; });
    });
    int rc = 1;
    try {
      drop_privileges({.user = "", .use_sudo_user = false});
    } catch (const PrivilegeError& e) {
      rc = std::string(e.what()).find("threads are running") != std::string::npos ? 0 : 2;
    }
    {
      std::lock_guard lock(m);
      done = true;
    }
    cv.notify_all();
    other.join();
    // Alone again, the drop works and a thread started afterwards inherits it.
    if (rc == 0) {
      drop_privileges({.user = "", .use_sudo_user = false});
      std::thread after([&] { rc = cap_eff_from_proc("/proc/thread-self/status") == 0 ? 0 : 3; });
      after.join();
    }
    return rc;
  });
  EXPECT_EQ(status, 0);
}

}  // namespace
}  // namespace rackcat::ecat
