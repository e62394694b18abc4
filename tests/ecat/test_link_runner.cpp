// Runner: what `rackcat run` prints and returns when it cannot start (one line, exit code 2),
// and that it serves a Segment on the wire. Tests that open a raw socket use lo and skip
// without CAP_NET_RAW; each runs in a child process because the runner drops privileges.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "ecat/host/runner.hpp"
#include "tests/ecat/link_test_util.hpp"

namespace rackcat::ecat {
namespace {

RunnerOptions options(const char* iface, const char* pcap = "") {
  RunnerOptions o;
  o.interface_name = iface;
  o.pcap_path = pcap;
  return o;
}

// Runs open() with stderr captured into a string.
int open_runner(Runner& runner, std::string& message) {
  FILE* err = std::tmpfile();
  const int rc = runner.open("rackcat", err);
  std::rewind(err);
  char buf[512] = {};
  const size_t n = std::fread(buf, 1, sizeof(buf) - 1, err);
  std::fclose(err);
  message.assign(buf, n);
  return rc;
}

TEST(LinkRunner, MissingInterfaceIsOneLineAndExitCode2) {
  Runner runner(options("rackcat-none0"));
  std::string message;
  EXPECT_EQ(open_runner(runner, message), 2);
  EXPECT_EQ(message, "rackcat: no such network interface: rackcat-none0\n");
}

TEST(LinkRunner, MissingPermissionIsOneLineAndExitCode2) {
  const int status = testutil::in_child([] {
    drop_privileges({.user = "", .use_sudo_user = false});
    Runner runner(options("lo"));
    std::string message;
    if (open_runner(runner, message) != 2) return 1;
    const bool one_line = message.find('\n') == message.size() - 1;
    return one_line && message.find("permission denied") != std::string::npos ? 0 : 2;
  });
  EXPECT_EQ(status, 0);
}

TEST(LinkRunner, UnwritableCaptureIsOneLineAndExitCode2) {
  if (!testutil::can_open_raw_socket()) GTEST_SKIP() << "needs root or CAP_NET_RAW";
  Runner runner(options("lo", "/nonexistent-dir/x.pcap"));
  std::string message;
  EXPECT_EQ(open_runner(runner, message), 2);
  EXPECT_EQ(message.find("rackcat: cannot create pcap file /nonexistent-dir/x.pcap"), 0u);
}

TEST(LinkRunner, AfterOpenNoCapabilityRemains) {
  if (!testutil::can_open_raw_socket()) GTEST_SKIP() << "needs root or CAP_NET_RAW";
  const int status = testutil::in_child([] {
    Runner runner(options("lo"));
    std::string message;
    if (open_runner(runner, message) != 0) return 1;
    const auto caps = read_capability_sets();
    return caps && caps->effective == 0 && caps->permitted == 0 ? 0 : 2;
  });
  EXPECT_EQ(status, 0);
}

}  // namespace
}  // namespace rackcat::ecat
