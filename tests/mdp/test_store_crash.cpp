// Durability of 0xFBF2: a child process stores parameter sets in a loop and is killed with
// SIGKILL at a random moment, hundreds of times; every time the file that remains loads and is
// exactly one of the sets the child stored (never a mix, never corrupt).
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <random>

#include "mdp/device.hpp"
#include "mdp/parameter_store.hpp"
#include "sdo_client.hpp"

namespace rackcat::mdp {
namespace {

std::vector<uint8_t> pattern(uint8_t fill, size_t n) {
  std::vector<uint8_t> v(n);
  for (size_t i = 0; i < n; ++i) v[i] = static_cast<uint8_t>(fill ^ (i * 7));
  return v;
}

void kill_after(pid_t child, std::mt19937& rng) {
  std::uniform_int_distribution<int> delay_us(0, 3000);
  ::usleep(static_cast<useconds_t>(delay_us(rng)));
  ::kill(child, SIGKILL);
  int status = 0;
  ::waitpid(child, &status, 0);
}

TEST(StoreCrash, KilledWhileStoringLeavesTheOldOrTheNewSet) {
  const std::string dir = ::testing::TempDir() + "/mdp_store_crash";
  std::filesystem::remove_all(dir);
  const ParameterStore store(dir);
  const uint32_t fp = 0xC0FFEE;
  const auto a = pattern(0xA5, 8192);
  const auto b = pattern(0x5A, 8192);
  std::string error;
  ASSERT_TRUE(store.save(fp, a, error)) << error;
  std::mt19937 rng(12345);
  int saw_a = 0, saw_b = 0;
  for (int i = 0; i < 300; ++i) {
    const pid_t child = ::fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
      std::string e;
      for (int k = 0;; ++k) store.save(fp, (k % 2) ? a : b, e);
    }
    kill_after(child, rng);
    std::vector<uint8_t> payload;
    std::string detail;
    ASSERT_EQ(store.load(fp, payload, detail), ParameterStore::LoadResult::Loaded)
        << "iteration " << i << ": " << detail;
    const bool is_a = payload == a;
    const bool is_b = payload == b;
    ASSERT_TRUE(is_a || is_b) << "iteration " << i << ": a mixed parameter set";
    saw_a += is_a;
    saw_b += is_b;
  }
  // Both outcomes happen, so the kills did land inside the store loop.
  EXPECT_GT(saw_a + saw_b, 0);
}

TEST(StoreCrash, KilledDuringStoreParametersCommandLeavesAConsistentDevice) {
  const std::string dir = ::testing::TempDir() + "/mdp_store_crash_device";
  std::filesystem::remove_all(dir);
  DeviceOptions opt;
  opt.state_dir = dir;
  const std::vector<uint8_t> save{0x73, 0x61, 0x76, 0x65};
  {
    Device d(default_rack(), opt);
    d.state_changed(EsmState::Init, EsmState::PreOp);
    testing::SdoClient sdo(d);
    ASSERT_EQ(sdo.write_text(0x2000, 0x04, "10.0.0.1"), 0u);
    ASSERT_EQ(sdo.download(0xFBF2, 1, save), 0u);
  }
  std::mt19937 rng(54321);
  for (int i = 0; i < 200; ++i) {
    const pid_t child = ::fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
      Device d(default_rack(), opt);
      d.state_changed(EsmState::Init, EsmState::PreOp);
      testing::SdoClient sdo(d);
      for (int k = 0;; ++k) {
        sdo.write_text(0x2000, 0x04, (k % 2) ? "10.0.0.1" : "10.0.0.2");
        sdo.write_u(0x2000, 0x0B, k % 2, 1);  // Detect Modules Override follows the address
        sdo.download(0xFBF2, 1, save);
      }
    }
    kill_after(child, rng);
    Device d(default_rack(), opt);
    d.state_changed(EsmState::Init, EsmState::PreOp);
    testing::SdoClient sdo(d);
    ASSERT_NE(d.load_report().find("loaded"), std::string::npos) << i << ": " << d.load_report();
    const std::string ip = sdo.read_text(0x2000, 0x04);
    const uint64_t dmo = sdo.read_u(0x2000, 0x0B);
    ASSERT_TRUE((ip == "10.0.0.1" && dmo == 1) || (ip == "10.0.0.2" && dmo == 0))
        << i << ": " << ip << " / " << dmo;
  }
}

}  // namespace
}  // namespace rackcat::mdp
