// The devices of one process share one background worker for their file commands (the
// thread count does not grow with the slave count): 32 devices, each storing its own
// parameters at once, use at most one thread besides the test's, and every store lands in its
// own device's file in submission order per device.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>

#include "mdp/background_worker.hpp"
#include "mdp/device.hpp"
#include "sdo_client.hpp"

namespace rackcat::mdp {
namespace {

using rackcat::EsmState;
using testing::SdoClient;

const std::vector<uint8_t> kStore{0x73, 0x61, 0x76, 0x65};  // "save" (guide: 0xFBF2)

int thread_count() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind("Threads:", 0) == 0) return std::stoi(line.substr(8));
  }
  return -1;
}

TEST(SharedWorker, ManyDevicesStoreOnOneThread) {
  const std::string dir = ::testing::TempDir() + "/mdp_shared_worker";
  std::filesystem::remove_all(dir);
  constexpr int kDevices = 32;
  std::vector<std::unique_ptr<Device>> devices;
  std::vector<std::unique_ptr<SdoClient>> clients;
  for (int i = 0; i < kDevices; ++i) {
    DeviceOptions opt;
    opt.state_dir = dir + "/" + std::to_string(i);
    devices.push_back(std::make_unique<Device>(default_rack(), opt));
    clients.push_back(std::make_unique<SdoClient>(*devices.back()));
    devices.back()->state_changed(EsmState::Init, EsmState::PreOp);
  }
  // Prime the shared worker (started with its first job), then count.
  ASSERT_EQ(clients[0]->download(0xFBF2, 1, kStore), 0u);
  const int before = thread_count();
  for (int i = 0; i < kDevices; ++i) {
    const std::string ip = "10.0.0." + std::to_string(i + 1);
    ASSERT_EQ(clients[i]->write_text(0x2000, 0x04, ip), 0u);
    ASSERT_EQ(clients[i]->download(0xFBF2, 1, kStore), 0u);
  }
  EXPECT_EQ(thread_count(), before);
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  for (int i = 0; i < kDevices; ++i) {
    uint64_t status = clients[i]->read_u(0xFBF2, 2);
    while (status == 255 && std::chrono::steady_clock::now() < give_up) {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
      status = clients[i]->read_u(0xFBF2, 2);
    }
    EXPECT_EQ(status, 0u) << "device " << i;
  }
  EXPECT_EQ(thread_count(), before);
  // A restart of every device reads its own stored address back.
  clients.clear();
  devices.clear();
  for (int i = 0; i < kDevices; ++i) {
    DeviceOptions opt;
    opt.state_dir = dir + "/" + std::to_string(i);
    Device d(default_rack(), opt);
    SdoClient c(d);
    d.state_changed(EsmState::Init, EsmState::PreOp);
    EXPECT_EQ(c.read_text(0x2000, 0x04), "10.0.0." + std::to_string(i + 1)) << "device " << i;
  }
}

// Clients destroyed while scheduled or running: forget() waits for a running job and drops the
// queued entry, so the worker never runs a destroyed client (ParameterWriter's destructor
// waits for its own jobs before it forgets).
TEST(SharedWorker, ClientsLeaveOnlyWhenTheirJobsAreDone) {
  struct Counter final : BackgroundWorker::Client {
    BackgroundWorker& worker;
    std::atomic<int> left{100};
    std::atomic<int> done{0};
    explicit Counter(BackgroundWorker& w) : worker(w) {}
    ~Counter() { worker.forget(*this); }
    Counter(const Counter&) = delete;
    Counter& operator=(const Counter&) = delete;
    bool run_one() override {
      if (left.load() == 0) return false;
      --left;
      ++done;
      return left.load() > 0;
    }
  };
  BackgroundWorker worker;
  for (int round = 0; round < 50; ++round) {
    Counter a(worker), b(worker);
    worker.schedule(a);
    worker.schedule(b);
    worker.schedule(a);  // already scheduled: no-op
  }
  Counter c(worker);
  worker.schedule(c);
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (c.done.load() < 100 && std::chrono::steady_clock::now() < give_up) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  EXPECT_EQ(c.done.load(), 100);
}

}  // namespace
}  // namespace rackcat::mdp
