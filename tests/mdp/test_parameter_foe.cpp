// parameters.bin over FoE (mdp/file_access.hpp, docs/FOE.md) does its disk work on the
// background worker, never on the device thread: with the worker held (WorkerGate) a read
// request gets no reply yet (deferred, ETG.1000.6 §5.8: a read is never answered Busy) and the
// last Data of a write gets Busy (ETG.1000.6 §5.8 "Busy request": Done / Entire) with nothing
// changed on disk or in the objects; once the worker has run, the read's Data 1 goes out from
// the mailbox poll and the write is acknowledged with the set applied. A save that fails is
// an FoE error and leaves the old set in the objects and on disk.
#include <signal.h>
#include <sys/resource.h>

#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <thread>

#include "base/little_endian.hpp"
#include "foe/foe_header.hpp"
#include "mdp/device.hpp"
#include "sdo_client.hpp"
#include "tests/support/worker_gate.hpp"

namespace rackcat::mdp {
namespace {

using Bytes = std::vector<uint8_t>;
using foe::OpCode;
using rackcat::EsmState;
using rackcat::mdp::testing::SdoClient;

constexpr uint32_t kPassword = 0x52434657;   // the default FoE password, docs/FOE.md
constexpr size_t kMailboxData = 122;         // SM0/SM1 of 128 bytes minus the mailbox header
const Bytes kStore{0x73, 0x61, 0x76, 0x65};  // "save" (guide: 0xFBF2)

Bytes file_bytes(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return Bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// The master's side of FoE, written from ETG.1000.6 §5.8: 6-byte header (OpCode, reserved,
// UINT32 password / packet number / error code), then the name or the data.
class FoeMaster {
 public:
  explicit FoeMaster(Device& d) : device_(d) {}

  Bytes send(OpCode op, uint32_t value, std::span<const uint8_t> data = {}) {
    Bytes req(foe::FoeHeader::kSize);
    foe::FoeHeader{static_cast<uint8_t>(op), value}.encode(req);
    req.insert(req.end(), data.begin(), data.end());
    Bytes reply(kMailboxData);
    const auto a = device_.foe_request(req, kMailboxData, reply);
    EXPECT_EQ(a.error, mailbox::Error::None);
    reply.resize(a.length);
    return reply;
  }
  Bytes request(OpCode op, const std::string& name) {
    return send(op, kPassword, {reinterpret_cast<const uint8_t*>(name.data()), name.size()});
  }
  // The mailbox poll (SM1 free): the deferred reply of a read, if there is one.
  Bytes poll() {
    Bytes reply(kMailboxData);
    reply.resize(device_.foe_poll(reply));
    return reply;
  }
  // Polls until a reply comes (bounded only so that a broken worker fails, not hangs).
  Bytes poll_until_reply() {
    const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    Bytes r = poll();
    while (r.empty() && std::chrono::steady_clock::now() < give_up) {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
      r = poll();
    }
    return r;
  }
  // The rest of a read whose Data 1 is `first`: acknowledges each Data until the short one.
  Bytes read_rest(Bytes first) {
    Bytes file;
    Bytes r = std::move(first);
    for (uint32_t packet = 1;; ++packet) {
      EXPECT_EQ(r.size() >= 6 ? r[0] : 0, static_cast<uint8_t>(OpCode::Data));
      if (r.size() < 6 || r[0] != static_cast<uint8_t>(OpCode::Data)) return {};
      EXPECT_EQ(le::get32(&r[2]), packet);
      file.insert(file.end(), r.begin() + 6, r.end());
      const bool last = r.size() < kMailboxData;
      r = send(OpCode::Ack, packet);
      if (last) {
        EXPECT_TRUE(r.empty());
        return file;
      }
    }
  }
  // A whole read: the request, Data 1 when the worker has the file, then the rest.
  Bytes read(const std::string& name) {
    Bytes r = request(OpCode::ReadRequest, name);
    if (r.empty()) r = poll_until_reply();
    return read_rest(std::move(r));
  }
  // Write request and every Data; returns the reply to the last Data.
  Bytes write(const std::string& name, const Bytes& file) {
    Bytes r = request(OpCode::WriteRequest, name);
    EXPECT_EQ(r, (Bytes{4, 0, 0, 0, 0, 0}));  // Ack 0
    constexpr size_t kChunk = kMailboxData - foe::FoeHeader::kSize;
    size_t at = 0;
    for (uint32_t packet = 1;; ++packet) {
      const size_t n = std::min(kChunk, file.size() - at);
      last_packet = packet;
      r = send(OpCode::Data, packet, {file.data() + at, n});
      at += n;
      if (n < kChunk) return r;
    }
  }
  // The master's repeat of the last Data after a Busy (ETG.1000.6 §5.8).
  Bytes repeat_last_data() { return send(OpCode::Data, last_packet); }
  uint32_t last_packet = 0;

 private:
  Device& device_;
};

bool is(const Bytes& r, OpCode op) {
  return r.size() >= 6 && r[0] == static_cast<uint8_t>(op);
}
uint32_t value_of(const Bytes& r) {
  return r.size() >= 6 ? le::get32(&r[2]) : 0xFFFFFFFF;
}

class ParameterFoe : public ::testing::Test {
 protected:
  std::filesystem::path root =
      std::filesystem::path(::testing::TempDir()) /
      ("mdp_parameter_foe_" +
       std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
  base::BackgroundWorker worker;  // this test's own: the gate holds nothing else

  void SetUp() override { std::filesystem::remove_all(root); }
  void TearDown() override { std::filesystem::remove_all(root); }

  std::unique_ptr<Device> make(const std::string& name) {
    DeviceOptions opt;
    opt.state_dir = (root / name).string();
    opt.worker = &worker;
    auto d = std::make_unique<Device>(default_rack(), opt);
    d->state_changed(EsmState::Init, EsmState::PreOp);
    return d;
  }
  // Stores the current parameters with 0xFBF2 and waits for the worker.
  static void store(Device& d) {
    SdoClient sdo(d);
    ASSERT_EQ(sdo.download(0xFBF2, 1, kStore), 0u);
    const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    uint64_t status = sdo.read_u(0xFBF2, 2);
    while (status == 255 && std::chrono::steady_clock::now() < give_up) {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
      status = sdo.read_u(0xFBF2, 2);
    }
    ASSERT_EQ(status, 0u);
  }
  static std::string address(Device& d) { return SdoClient(d).read_text(0x2000, 0x04); }
  // A parameter file from a device whose stored set has IP address `ip`.
  Bytes backup_with(const std::string& ip) {
    auto source = make("source-" + ip);
    EXPECT_EQ(SdoClient(*source).write_text(0x2000, 0x04, ip), 0u);
    store(*source);
    FoeMaster m(*source);
    return m.read("parameters.bin");
  }
};

// The read is queued behind the 0xFBF2 store the master asked for before it (the worker runs a
// device's jobs in order): the device thread neither waits for the store nor reads the disk.
TEST_F(ParameterFoe, ReadIsDeferredBehindAPendingStoreAndServedFromThePoll) {
  auto d = make("device");
  SdoClient sdo(*d);
  ASSERT_EQ(sdo.write_text(0x2000, 0x04, "10.0.0.9"), 0u);
  store(*d);
  FoeMaster m(*d);
  const Bytes before = m.read("parameters.bin");
  ASSERT_FALSE(before.empty());
  EXPECT_EQ(before, file_bytes(root / "device" / "parameters.bin"));
  {
    rackcat::testing::WorkerGate gate(worker);
    ASSERT_EQ(sdo.write_text(0x2000, 0x04, "10.0.0.10"), 0u);
    ASSERT_EQ(sdo.download(0xFBF2, 1, kStore), 0u);                         // queued, not run
    EXPECT_TRUE(m.request(OpCode::ReadRequest, "parameters.bin").empty());  // deferred, no Busy
    EXPECT_TRUE(d->mailbox_pending());
    EXPECT_TRUE(m.poll().empty());
    EXPECT_TRUE(m.poll().empty());
    EXPECT_EQ(file_bytes(root / "device" / "parameters.bin"), before);  // nothing stored yet
    gate.open();
  }
  const Bytes after = m.read_rest(m.poll_until_reply());
  EXPECT_NE(after, before);
  EXPECT_EQ(after, file_bytes(root / "device" / "parameters.bin"));  // the store ran first
  const std::string ip = "10.0.0.10";
  EXPECT_NE(std::search(after.begin(), after.end(), ip.begin(), ip.end()), after.end());
}

// A stale read (a new request, ESM back to INIT) is dropped: its late result sends nothing.
TEST_F(ParameterFoe, AbandonedReadSendsNothingAndANewOneIsServed) {
  auto d = make("device");
  FoeMaster m(*d);
  {
    rackcat::testing::WorkerGate gate(worker);
    EXPECT_TRUE(m.request(OpCode::ReadRequest, "parameters.bin").empty());
    d->state_changed(EsmState::PreOp, EsmState::Init);  // the mailbox restarts
    d->state_changed(EsmState::Init, EsmState::PreOp);
    EXPECT_TRUE(m.request(OpCode::ReadRequest, "parameters.bin").empty());
    EXPECT_TRUE(m.request(OpCode::ReadRequest, "parameters.bin").empty());  // a third
    gate.open();
  }
  const Bytes file = m.read_rest(m.poll_until_reply());
  EXPECT_FALSE(file.empty());
  { rackcat::testing::WorkerGate sync(worker); }  // every job queued before has run
  EXPECT_TRUE(m.poll().empty());                  // one reply, for the last request only
  {
    rackcat::testing::WorkerGate gate(worker);
    EXPECT_TRUE(m.request(OpCode::ReadRequest, "parameters.bin").empty());
    d->state_changed(EsmState::PreOp, EsmState::Init);
    gate.open();
  }
  { rackcat::testing::WorkerGate sync(worker); }
  EXPECT_TRUE(m.poll().empty());
  EXPECT_FALSE(d->mailbox_pending());
}

TEST_F(ParameterFoe, RestoreAnswersBusyWhileTheWorkerSavesThenAppliesTheSet) {
  const Bytes backup = backup_with("10.0.0.21");
  auto d = make("replacement");
  const std::string old_ip = address(*d);
  ASSERT_NE(old_ip, "10.0.0.21");
  FoeMaster m(*d);
  {
    rackcat::testing::WorkerGate gate(worker);
    const Bytes r = m.write("parameters.bin", backup);
    EXPECT_TRUE(is(r, OpCode::Busy)) << r.size();
    EXPECT_EQ(value_of(r), 0x00010000u);  // Done 0 of Entire 1
    EXPECT_TRUE(is(m.repeat_last_data(), OpCode::Busy));
    EXPECT_EQ(address(*d), old_ip);  // nothing applied yet
    EXPECT_FALSE(std::filesystem::exists(root / "replacement" / "parameters.bin"));
    // Another write meanwhile is refused, not queued over the running one.
    EXPECT_EQ(value_of(m.request(OpCode::WriteRequest, "parameters.bin")), 0x8002u);
    gate.open();
  }
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  Bytes r = m.repeat_last_data();
  while (is(r, OpCode::Busy) && std::chrono::steady_clock::now() < give_up) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
    r = m.repeat_last_data();
  }
  EXPECT_TRUE(is(r, OpCode::Ack));
  EXPECT_EQ(value_of(r), m.last_packet);
  EXPECT_EQ(address(*d), "10.0.0.21");
  EXPECT_EQ(file_bytes(root / "replacement" / "parameters.bin"), backup);
  EXPECT_EQ(m.read("parameters.bin"), backup);
}

// A bad file is refused on the device thread at once (nothing queued): the worker stays held.
TEST_F(ParameterFoe, DamagedFileIsRefusedAtOnceWithoutTheWorker) {
  Bytes backup = backup_with("10.0.0.22");
  backup[backup.size() / 2] ^= 0x01;
  auto d = make("replacement");
  FoeMaster m(*d);
  rackcat::testing::WorkerGate gate(worker);
  const Bytes r = m.write("parameters.bin", backup);
  EXPECT_TRUE(is(r, OpCode::Error));
  EXPECT_EQ(value_of(r), 0x800Cu);  // Wrong checksum
  EXPECT_FALSE(std::filesystem::exists(root / "replacement" / "parameters.bin"));
}

// A save that fails on the worker (here the file size limit: EFBIG, a full disk for the device)
// is FoE Error 0x8003 Disk full; the old set stays in the objects and on disk.
TEST_F(ParameterFoe, FailedSaveIsDiskFullAndKeepsTheOldSet) {
  const Bytes backup = backup_with("10.0.0.23");
  auto d = make("replacement");
  ASSERT_EQ(SdoClient(*d).write_text(0x2000, 0x04, "10.0.0.5"), 0u);
  store(*d);
  const Bytes stored = file_bytes(root / "replacement" / "parameters.bin");
  FoeMaster m(*d);
  struct sigaction ignore {};
  ignore.sa_handler = SIG_IGN;
  struct sigaction old_action {};
  ASSERT_EQ(::sigaction(SIGXFSZ, &ignore, &old_action), 0);
  rlimit old_limit{};
  ASSERT_EQ(::getrlimit(RLIMIT_FSIZE, &old_limit), 0);
  rlimit small = old_limit;
  small.rlim_cur = 16;  // far below any parameter file
  ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &small), 0);
  Bytes r = m.write("parameters.bin", backup);
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (is(r, OpCode::Busy) && std::chrono::steady_clock::now() < give_up) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
    r = m.repeat_last_data();
  }
  ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &old_limit), 0);
  ASSERT_EQ(::sigaction(SIGXFSZ, &old_action, nullptr), 0);
  EXPECT_TRUE(is(r, OpCode::Error));
  EXPECT_EQ(value_of(r), 0x8003u);
  EXPECT_EQ(address(*d), "10.0.0.5");
  EXPECT_EQ(file_bytes(root / "replacement" / "parameters.bin"), stored);
  EXPECT_FALSE(std::filesystem::exists(root / "replacement" / "parameters.bin.tmp"));
  EXPECT_EQ(m.read("parameters.bin"), stored);
}

// The mailbox restarting (INIT) or the device going away while a restore waits for the worker:
// the save completes (it is durable once begun) and is applied; a device destroyed meanwhile
// waits for its queued jobs, which hold no pointer into it.
TEST_F(ParameterFoe, RestoreOutlivesAMailboxRestartAndTheDevice) {
  const Bytes backup = backup_with("10.0.0.24");
  auto d = make("replacement");
  {
    FoeMaster m(*d);
    rackcat::testing::WorkerGate gate(worker);
    EXPECT_TRUE(is(m.write("parameters.bin", backup), OpCode::Busy));
    d->state_changed(EsmState::PreOp, EsmState::Init);
    d->state_changed(EsmState::Init, EsmState::PreOp);
    gate.open();
  }
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (address(*d) != "10.0.0.24" && std::chrono::steady_clock::now() < give_up) {
    FoeMaster(*d).poll();
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  EXPECT_EQ(address(*d), "10.0.0.24");
  EXPECT_EQ(file_bytes(root / "replacement" / "parameters.bin"), backup);

  auto e = make("gone");
  {
    FoeMaster m(*e);
    rackcat::testing::WorkerGate gate(worker);
    ASSERT_EQ(SdoClient(*e).download(0xFBF2, 1, kStore), 0u);  // a store queued first
    EXPECT_TRUE(is(m.write("parameters.bin", backup), OpCode::Busy));
    // A read meanwhile is refused (the restore still runs), not queued.
    EXPECT_EQ(value_of(m.request(OpCode::ReadRequest, "parameters.bin")), 0x8002u);
    std::thread opener([&gate] {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      gate.open();
    });
    e.reset();  // waits for the queued store and save, then goes
    opener.join();
  }
  EXPECT_EQ(file_bytes(root / "gone" / "parameters.bin"), backup);
}

// mailbox_pending() answers from a hint (issue 16: O(1) per slave and frame) that everything
// able to make the mailbox pending raises: here the worker finishing a command's file work
// with no request in between, and an Emergency.
TEST_F(ParameterFoe, MailboxPendingRisesWhenTheWorkerPublishesAResult) {
  auto d = make("device");
  SdoClient sdo(*d);
  uint8_t buf[256];
  {
    rackcat::testing::WorkerGate gate(worker);
    ASSERT_EQ(sdo.download(0xFBF2, 1, kStore), 0u);  // queued behind the gate
    while (d->coe_poll(buf) > 0) {
    }
    EXPECT_FALSE(d->mailbox_pending());
    EXPECT_FALSE(d->mailbox_pending());  // the hint is down: the same answer
    gate.open();
  }
  { rackcat::testing::WorkerGate sync(worker); }  // the store has run
  EXPECT_TRUE(d->mailbox_pending());              // without any request since
  while (d->coe_poll(buf) > 0) {
  }
  EXPECT_FALSE(d->mailbox_pending());  // the result was taken
  ASSERT_TRUE(d->raise_emergency(0x5000, 0x01));
  EXPECT_TRUE(d->mailbox_pending());
  EXPECT_GT(d->coe_poll(buf), 0u);
  EXPECT_FALSE(d->mailbox_pending());
}

}  // namespace
}  // namespace rackcat::mdp
