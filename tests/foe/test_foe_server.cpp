// Golden vectors for the FoE server, written from ETG.1000.6 §5.8 (FoE header: OpCode, Reserved,
// 32-bit Password / PacketNumber / ErrorCode / Done+Entire; Read 1, Write 2, Data 3, Ack 4,
// Error 5, Busy 6; error codes 0x8000.. with their standard texts), against an in-memory file
// backend. Every request and expected reply is spelled out byte by byte.
#include <gtest/gtest.h>

#include <map>
#include <string>
#include <vector>

#include "foe/foe_server.hpp"

namespace rackcat::foe {
namespace {

using Bytes = std::vector<uint8_t>;

Bytes cat(Bytes a, std::string_view s) {
  a.insert(a.end(), s.begin(), s.end());
  return a;
}

class MemoryBackend : public FileBackend {
 public:
  std::map<std::string, Bytes> files;
  uint32_t password = 0x12345678;
  int busy_polls = 0;  // how many times commit/poll_commit answer busy
  FoeError commit_error = FoeError::None;
  FoeError begin_error = FoeError::None;  // begin_write refuses with it (after the password)
  int aborts = 0;
  int writes = 0;
  std::string open_name;
  Bytes pending;
  bool finished = false;
  FoeError finished_error = FoeError::None;

  int read_busy_polls = 0;  // how many times read_file/poll_read answer busy
  int read_aborts = 0;
  std::string reading;

  ReadProgress read_file(std::string_view name, uint32_t pw, size_t, Bytes& out) override {
    if (pw != password) return {false, FoeError::NoRights};
    reading = std::string(name);
    return poll_read(out);
  }
  ReadProgress poll_read(Bytes& out) override {
    if (read_busy_polls > 0) {
      --read_busy_polls;
      return {true, FoeError::None};
    }
    auto it = files.find(reading);
    if (it == files.end()) return {false, FoeError::NotFound};
    out = it->second;
    return {false, FoeError::None};
  }
  void abort_read() override { ++read_aborts; }
  FoeError begin_write(std::string_view name, uint32_t pw) override {
    if (pw != password) return FoeError::NoRights;
    if (begin_error != FoeError::None) return begin_error;
    if (name.substr(0, 4) != "file") return FoeError::NotFound;
    open_name = std::string(name);
    pending.clear();
    finished = false;
    return FoeError::None;
  }
  FoeError write_data(std::span<const uint8_t> d) override {
    ++writes;
    pending.insert(pending.end(), d.begin(), d.end());
    return FoeError::None;
  }
  CommitProgress commit() override { return poll_commit(); }
  CommitProgress poll_commit() override {
    if (finished) return {false, finished_error, 0, 0};
    if (busy_polls > 0) {
      --busy_polls;
      return {true, FoeError::None, 1, 2};
    }
    finished = true;
    finished_error = commit_error;
    if (commit_error == FoeError::None) files[open_name] = pending;
    return {false, commit_error, 0, 0};
  }
  void abort_write() override {
    ++aborts;
    pending.clear();
  }
};

// Receive mailbox data of 16 bytes: FoE header + 10 data bytes per full packet. Send mailbox
// data of 16 bytes likewise.
constexpr size_t kCapacity = 16;

class FoeServerTest : public ::testing::Test {
 protected:
  MemoryBackend backend;
  uint64_t now = 1000;
  FoeServer server{backend, FoeLimits{16, 1000, 10'000}, [this] { return now; }};

  Bytes send(const Bytes& req, size_t reply_size = kCapacity) {
    Bytes reply(reply_size, 0xEE);
    const auto r = server.handle(req, kCapacity, reply);
    reply.resize(r.length);
    return reply;
  }
};

const Bytes kWrqFileA = cat({0x02, 0x00, 0x78, 0x56, 0x34, 0x12}, "fileA");
const Bytes kAck0 = {0x04, 0x00, 0x00, 0x00, 0x00, 0x00};

TEST_F(FoeServerTest, WriteRequestIsAcknowledgedWithPacketZero) {
  EXPECT_EQ(send(kWrqFileA), kAck0);
}

TEST_F(FoeServerTest, WriteOfTwoPacketsEndsWithTheShortOne) {
  ASSERT_EQ(send(kWrqFileA), kAck0);
  EXPECT_EQ(send(cat({0x03, 0x00, 0x01, 0x00, 0x00, 0x00}, "0123456789")),
            (Bytes{0x04, 0x00, 0x01, 0x00, 0x00, 0x00}));
  EXPECT_EQ(send(cat({0x03, 0x00, 0x02, 0x00, 0x00, 0x00}, "abc")),
            (Bytes{0x04, 0x00, 0x02, 0x00, 0x00, 0x00}));
  EXPECT_EQ(backend.files["fileA"], cat({}, "0123456789abc"));
  EXPECT_TRUE(server.idle());
}

TEST_F(FoeServerTest, WriteOfAnExactMultipleEndsWithAnEmptyData) {
  ASSERT_EQ(send(kWrqFileA), kAck0);
  ASSERT_EQ(send(cat({0x03, 0x00, 0x01, 0x00, 0x00, 0x00}, "0123456789")),
            (Bytes{0x04, 0x00, 0x01, 0x00, 0x00, 0x00}));
  EXPECT_FALSE(backend.files.count("fileA"));  // not yet: a full packet is never the last
  EXPECT_EQ(send({0x03, 0x00, 0x02, 0x00, 0x00, 0x00}),
            (Bytes{0x04, 0x00, 0x02, 0x00, 0x00, 0x00}));
  EXPECT_EQ(backend.files["fileA"], cat({}, "0123456789"));
}

TEST_F(FoeServerTest, BusyWhileCommittingThenAckOfTheRepeatedLastPacket) {
  backend.busy_polls = 2;
  ASSERT_EQ(send(kWrqFileA), kAck0);
  const Bytes last = cat({0x03, 0x00, 0x01, 0x00, 0x00, 0x00}, "xyz");
  // Busy: Done = 1, Entire = 2 (two UINT16 in place of the packet number).
  EXPECT_EQ(send(last), (Bytes{0x06, 0x00, 0x01, 0x00, 0x02, 0x00}));
  EXPECT_TRUE(server.committing());
  EXPECT_EQ(send(last), (Bytes{0x06, 0x00, 0x01, 0x00, 0x02, 0x00}));
  EXPECT_EQ(send(last), (Bytes{0x04, 0x00, 0x01, 0x00, 0x00, 0x00}));
  EXPECT_EQ(backend.writes, 1);  // the repeats were not written again
  EXPECT_EQ(backend.files["fileA"], cat({}, "xyz"));
}

TEST_F(FoeServerTest, NewRequestDuringABusyCommitIsAccessDenied) {
  backend.busy_polls = 5;
  ASSERT_EQ(send(kWrqFileA), kAck0);
  ASSERT_EQ(send(cat({0x03, 0x00, 0x01, 0x00, 0x00, 0x00}, "x"))[0], 0x06);
  EXPECT_EQ(send(kWrqFileA, 64), cat({0x05, 0x00, 0x02, 0x80, 0x00, 0x00}, "Access denied"));
}

// The mailbox restarts (INIT) while a commit runs: not waited for; a new request meanwhile is
// Access denied, and once the commit is done the server is idle again.
TEST_F(FoeServerTest, ResetDuringACommitDoesNotWaitForIt) {
  backend.busy_polls = 4;  // each poll_commit below takes one
  ASSERT_EQ(send(kWrqFileA), kAck0);
  ASSERT_EQ(send(cat({0x03, 0x00, 0x01, 0x00, 0x00, 0x00}, "x"))[0], 0x06);  // Busy
  server.reset();  // still busy: returns at once
  EXPECT_TRUE(server.committing());
  EXPECT_EQ(send(kWrqFileA, 64), cat({0x05, 0x00, 0x02, 0x80, 0x00, 0x00}, "Access denied"));
  server.reset();  // the last busy poll
  EXPECT_TRUE(server.committing());
  server.reset();  // done now: idle
  EXPECT_TRUE(server.idle());
  EXPECT_EQ(backend.files["fileA"], cat({}, "x"));
  EXPECT_EQ(send(kWrqFileA), kAck0);
}

TEST_F(FoeServerTest, RefusedCommitAnswersTheBackendsError) {
  backend.commit_error = FoeError::WrongChecksum;
  ASSERT_EQ(send(kWrqFileA), kAck0);
  // 0x800C "Wrong checksum" does not fit 10 bytes of text: cut to the reply.
  EXPECT_EQ(send(cat({0x03, 0x00, 0x01, 0x00, 0x00, 0x00}, "x")),
            cat({0x05, 0x00, 0x0C, 0x80, 0x00, 0x00}, "Wrong chec"));
  EXPECT_EQ(send(cat({0x03, 0x00, 0x01, 0x00, 0x00, 0x00}, "x"), 64),
            cat({0x05, 0x00, 0x04, 0x80, 0x00, 0x00}, "Illegal"));
  EXPECT_FALSE(backend.files.count("fileA"));
}

TEST_F(FoeServerTest, FullErrorTextWhenTheReplyHasRoom) {
  backend.commit_error = FoeError::FirmwareDoesNotFitHardware;
  ASSERT_EQ(send(kWrqFileA), kAck0);
  EXPECT_EQ(send(cat({0x03, 0x00, 0x01, 0x00, 0x00, 0x00}, "x"), 64),
            cat({0x05, 0x00, 0x0D, 0x80, 0x00, 0x00}, "Firmware does not fit for hardware"));
}

TEST_F(FoeServerTest, OutOfOrderPacketIsPacketNumberWrongAndEndsTheWrite) {
  ASSERT_EQ(send(kWrqFileA), kAck0);
  EXPECT_EQ(send(cat({0x03, 0x00, 0x02, 0x00, 0x00, 0x00}, "0123456789"), 64),
            cat({0x05, 0x00, 0x05, 0x80, 0x00, 0x00}, "Packet number wrong"));
  EXPECT_EQ(backend.aborts, 1);
  EXPECT_TRUE(server.idle());
}

TEST_F(FoeServerTest, RepeatedDataIsAcknowledgedAgainNotWrittenTwice) {
  ASSERT_EQ(send(kWrqFileA), kAck0);
  const Bytes d1 = cat({0x03, 0x00, 0x01, 0x00, 0x00, 0x00}, "0123456789");
  ASSERT_EQ(send(d1), (Bytes{0x04, 0x00, 0x01, 0x00, 0x00, 0x00}));
  EXPECT_EQ(send(d1), (Bytes{0x04, 0x00, 0x01, 0x00, 0x00, 0x00}));
  ASSERT_EQ(send({0x03, 0x00, 0x02, 0x00, 0x00, 0x00}),
            (Bytes{0x04, 0x00, 0x02, 0x00, 0x00, 0x00}));
  EXPECT_EQ(backend.files["fileA"], cat({}, "0123456789"));
}

TEST_F(FoeServerTest, DataLongerThanTheMailboxAllowsIsIllegal) {
  ASSERT_EQ(send(kWrqFileA), kAck0);
  Bytes reply(64);
  const Bytes big = cat({0x03, 0x00, 0x01, 0x00, 0x00, 0x00}, "0123456789X");
  const auto r = server.handle(big, kCapacity, reply);
  reply.resize(r.length);
  EXPECT_EQ(reply, cat({0x05, 0x00, 0x04, 0x80, 0x00, 0x00}, "Illegal"));
}

TEST_F(FoeServerTest, FileLargerThanTheCapIsDiskFull) {
  FoeServer small{backend, FoeLimits{16, 15, 10'000}, [this] { return now; }};
  Bytes reply(64);
  ASSERT_EQ(small.handle(kWrqFileA, kCapacity, reply).length, 6u);
  ASSERT_EQ(small.handle(cat({0x03, 0x00, 0x01, 0x00, 0x00, 0x00}, "0123456789"), kCapacity, reply)
                .length,
            6u);
  const auto r =
      small.handle(cat({0x03, 0x00, 0x02, 0x00, 0x00, 0x00}, "012345"), kCapacity, reply);
  reply.resize(r.length);
  EXPECT_EQ(reply, cat({0x05, 0x00, 0x03, 0x80, 0x00, 0x00}, "Disk full"));
  EXPECT_EQ(backend.aborts, 1);
}

TEST_F(FoeServerTest, WrongPasswordIsNoRights) {
  EXPECT_EQ(send(cat({0x02, 0x00, 0x00, 0x00, 0x00, 0x00}, "fileA"), 64),
            cat({0x05, 0x00, 0x0A, 0x80, 0x00, 0x00}, "No rights"));
  EXPECT_EQ(send(cat({0x01, 0x00, 0x01, 0x00, 0x00, 0x00}, "fileA"), 64),
            cat({0x05, 0x00, 0x0A, 0x80, 0x00, 0x00}, "No rights"));
}

TEST_F(FoeServerTest, NameLongerThanTheLimitIsIllegalEmptyNameIsNotFound) {
  EXPECT_EQ(send(cat({0x02, 0x00, 0x78, 0x56, 0x34, 0x12}, "file_0123456789ab"), 64),
            cat({0x05, 0x00, 0x04, 0x80, 0x00, 0x00}, "Illegal"));
  EXPECT_EQ(send({0x02, 0x00, 0x78, 0x56, 0x34, 0x12}, 64),
            cat({0x05, 0x00, 0x01, 0x80, 0x00, 0x00}, "Not found"));
}

TEST_F(FoeServerTest, NulTerminatedNameEndsAtTheNul) {
  Bytes req = kWrqFileA;
  req.push_back(0);
  req.push_back('Z');
  EXPECT_EQ(send(req), kAck0);
  EXPECT_EQ(backend.open_name, "fileA");
}

TEST_F(FoeServerTest, ReadSendsNumberedDataUntilTheShortPacket) {
  backend.files["fileR"] = cat({}, "0123456789abc");
  EXPECT_EQ(send(cat({0x01, 0x00, 0x78, 0x56, 0x34, 0x12}, "fileR")),
            cat({0x03, 0x00, 0x01, 0x00, 0x00, 0x00}, "0123456789"));
  EXPECT_EQ(send({0x04, 0x00, 0x01, 0x00, 0x00, 0x00}),
            cat({0x03, 0x00, 0x02, 0x00, 0x00, 0x00}, "abc"));
  EXPECT_EQ(send({0x04, 0x00, 0x02, 0x00, 0x00, 0x00}), Bytes{});  // last packet acknowledged
  EXPECT_TRUE(server.idle());
}

TEST_F(FoeServerTest, ReadOfAnExactMultipleEndsWithAnEmptyData) {
  backend.files["fileR"] = cat({}, "0123456789");
  EXPECT_EQ(send(cat({0x01, 0x00, 0x78, 0x56, 0x34, 0x12}, "fileR")),
            cat({0x03, 0x00, 0x01, 0x00, 0x00, 0x00}, "0123456789"));
  EXPECT_EQ(send({0x04, 0x00, 0x01, 0x00, 0x00, 0x00}),
            (Bytes{0x03, 0x00, 0x02, 0x00, 0x00, 0x00}));
  EXPECT_EQ(send({0x04, 0x00, 0x02, 0x00, 0x00, 0x00}), Bytes{});
}

// A backend that fetches the file elsewhere (device/foe_files.hpp) answers busy: the read
// request gets no reply until poll() finds the file there, then Data 1 goes out from poll().
TEST_F(FoeServerTest, ReadOfAFileFetchedElsewhereDefersTheFirstData) {
  backend.files["fileR"] = cat({}, "0123456789abc");
  backend.read_busy_polls = 2;  // busy for the request and the first poll
  EXPECT_EQ(send(cat({0x01, 0x00, 0x78, 0x56, 0x34, 0x12}, "fileR")), Bytes{});
  EXPECT_FALSE(server.idle());  // the mailbox stays pending (GenericDevice::mailbox_pending)
  Bytes reply(kCapacity, 0xEE);
  EXPECT_EQ(server.poll(reply), 0u);
  ASSERT_EQ(server.poll(reply), FoeHeader::kSize + 10);
  EXPECT_EQ(reply, cat({0x03, 0x00, 0x01, 0x00, 0x00, 0x00}, "0123456789"));
  EXPECT_EQ(server.poll(reply), 0u);  // sent once
  EXPECT_EQ(send({0x04, 0x00, 0x01, 0x00, 0x00, 0x00}),
            cat({0x03, 0x00, 0x02, 0x00, 0x00, 0x00}, "abc"));
  EXPECT_EQ(send({0x04, 0x00, 0x02, 0x00, 0x00, 0x00}), Bytes{});
  EXPECT_TRUE(server.idle());
}

TEST_F(FoeServerTest, DeferredReadOfAMissingFileAnswersItsErrorFromPoll) {
  backend.read_busy_polls = 2;  // busy for the request and the first poll
  EXPECT_EQ(send(cat({0x01, 0x00, 0x78, 0x56, 0x34, 0x12}, "nope")), Bytes{});
  Bytes reply(64, 0xEE);
  EXPECT_EQ(server.poll(reply), 0u);
  reply.resize(server.poll(reply));
  EXPECT_EQ(reply, cat({0x05, 0x00, 0x01, 0x80, 0x00, 0x00}, "Not found"));
  EXPECT_TRUE(server.idle());
}

TEST_F(FoeServerTest, DeferredReadIsAbandonedByANewRequestATimeoutOrAReset) {
  backend.files["fileR"] = cat({}, "x");
  backend.read_busy_polls = 100;
  const Bytes rrq = cat({0x01, 0x00, 0x78, 0x56, 0x34, 0x12}, "fileR");
  ASSERT_EQ(send(rrq), Bytes{});
  EXPECT_EQ(send(kWrqFileA), kAck0);  // a new request: the read is dropped
  EXPECT_EQ(backend.read_aborts, 1);
  ASSERT_EQ(send(rrq), Bytes{});
  EXPECT_EQ(backend.aborts, 1);  // ...and so was the write
  now += 10'001;
  Bytes reply(kCapacity);
  EXPECT_EQ(server.poll(reply), 0u);
  EXPECT_TRUE(server.idle());
  EXPECT_EQ(backend.read_aborts, 2);
  ASSERT_EQ(send(rrq), Bytes{});
  server.reset();
  EXPECT_TRUE(server.idle());
  EXPECT_EQ(backend.read_aborts, 3);
  // An Ack before any Data is out of turn.
  ASSERT_EQ(send(rrq), Bytes{});
  EXPECT_EQ(send({0x04, 0x00, 0x01, 0x00, 0x00, 0x00}, 64),
            cat({0x05, 0x00, 0x04, 0x80, 0x00, 0x00}, "Illegal"));
  EXPECT_EQ(backend.read_aborts, 4);
}

TEST_F(FoeServerTest, ReadOfAMissingFileIsNotFound) {
  EXPECT_EQ(send(cat({0x01, 0x00, 0x78, 0x56, 0x34, 0x12}, "nope"), 64),
            cat({0x05, 0x00, 0x01, 0x80, 0x00, 0x00}, "Not found"));
}

TEST_F(FoeServerTest, AckWithTheWrongPacketNumberIsPacketNumberWrong) {
  backend.files["fileR"] = cat({}, "0123456789abc");
  ASSERT_EQ(send(cat({0x01, 0x00, 0x78, 0x56, 0x34, 0x12}, "fileR")).size(), 16u);
  EXPECT_EQ(send({0x04, 0x00, 0x02, 0x00, 0x00, 0x00}, 64),
            cat({0x05, 0x00, 0x05, 0x80, 0x00, 0x00}, "Packet number wrong"));
  EXPECT_TRUE(server.idle());
}

TEST_F(FoeServerTest, RequestsOutOfTurnAreIllegal) {
  const Bytes illegal = cat({0x05, 0x00, 0x04, 0x80, 0x00, 0x00}, "Illegal");
  EXPECT_EQ(send({0x04, 0x00, 0x01, 0x00, 0x00, 0x00}, 64), illegal);  // Ack, no read
  EXPECT_EQ(send({0x03, 0x00, 0x01, 0x00, 0x00, 0x00}, 64), illegal);  // Data, no write
  EXPECT_EQ(send({0x06, 0x00, 0x00, 0x00, 0x00, 0x00}, 64), illegal);  // Busy from the master
  EXPECT_EQ(send({0x07, 0x00, 0x00, 0x00, 0x00, 0x00}, 64), illegal);  // no such OpCode
  EXPECT_EQ(send({0x00, 0x00, 0x00, 0x00, 0x00, 0x00}, 64), illegal);
}

TEST_F(FoeServerTest, ErrorFromTheMasterEndsTheWriteWithoutReply) {
  ASSERT_EQ(send(kWrqFileA), kAck0);
  EXPECT_EQ(send(cat({0x05, 0x00, 0x00, 0x80, 0x00, 0x00}, "stop")), Bytes{});
  EXPECT_EQ(backend.aborts, 1);
  EXPECT_EQ(send({0x03, 0x00, 0x01, 0x00, 0x00, 0x00}, 64),
            cat({0x05, 0x00, 0x04, 0x80, 0x00, 0x00}, "Illegal"));
}

TEST_F(FoeServerTest, AbandonedTransferTimesOut) {
  ASSERT_EQ(send(kWrqFileA), kAck0);
  now += 10'001;
  server.tick();
  EXPECT_TRUE(server.idle());
  EXPECT_EQ(backend.aborts, 1);
  EXPECT_EQ(send(cat({0x03, 0x00, 0x01, 0x00, 0x00, 0x00}, "x"), 64),
            cat({0x05, 0x00, 0x04, 0x80, 0x00, 0x00}, "Illegal"));
}

TEST_F(FoeServerTest, TransferWithinTheTimeoutContinues) {
  ASSERT_EQ(send(kWrqFileA), kAck0);
  now += 9'999;
  EXPECT_EQ(send(cat({0x03, 0x00, 0x01, 0x00, 0x00, 0x00}, "x")),
            (Bytes{0x04, 0x00, 0x01, 0x00, 0x00, 0x00}));
}

TEST_F(FoeServerTest, NewRequestAbortsAStaleOne) {
  ASSERT_EQ(send(kWrqFileA), kAck0);
  ASSERT_EQ(send(cat({0x03, 0x00, 0x01, 0x00, 0x00, 0x00}, "0123456789"))[0], 0x04);
  EXPECT_EQ(send(cat({0x02, 0x00, 0x78, 0x56, 0x34, 0x12}, "fileB")), kAck0);
  EXPECT_EQ(backend.aborts, 1);
  EXPECT_EQ(send(cat({0x03, 0x00, 0x01, 0x00, 0x00, 0x00}, "new")),
            (Bytes{0x04, 0x00, 0x01, 0x00, 0x00, 0x00}));
  EXPECT_EQ(backend.files["fileB"], cat({}, "new"));
  EXPECT_FALSE(backend.files.count("fileA"));
}

TEST_F(FoeServerTest, RequestShorterThanTheFoeHeaderIsReportedForAMailboxError) {
  Bytes reply(16);
  const Bytes five = {0x02, 0x00, 0x00, 0x00, 0x00};
  const auto r = server.handle(five, kCapacity, reply);
  EXPECT_TRUE(r.too_short);
  EXPECT_EQ(r.length, 0u);
}

// Every FoE error code with its text (ETG.1000.6 §5.8, table of FoE error codes; 0x800C-0x8012
// as SOEM and the ETG firmware-update practice name them): the write request the backend
// refuses is answered by Error (OpCode 5), the code as UINT32 little-endian, then the text.
TEST_F(FoeServerTest, EveryErrorCodeGoesOnTheWireWithItsText) {
  struct Golden {
    FoeError error;
    Bytes reply;
  };
  const Golden table[] = {
      {FoeError::NotDefined, cat({0x05, 0x00, 0x00, 0x80, 0x00, 0x00}, "Not defined")},
      {FoeError::NotFound, cat({0x05, 0x00, 0x01, 0x80, 0x00, 0x00}, "Not found")},
      {FoeError::AccessDenied, cat({0x05, 0x00, 0x02, 0x80, 0x00, 0x00}, "Access denied")},
      {FoeError::DiskFull, cat({0x05, 0x00, 0x03, 0x80, 0x00, 0x00}, "Disk full")},
      {FoeError::Illegal, cat({0x05, 0x00, 0x04, 0x80, 0x00, 0x00}, "Illegal")},
      {FoeError::PacketNumberWrong,
       cat({0x05, 0x00, 0x05, 0x80, 0x00, 0x00}, "Packet number wrong")},
      {FoeError::AlreadyExists, cat({0x05, 0x00, 0x06, 0x80, 0x00, 0x00}, "Already exists")},
      {FoeError::NoUser, cat({0x05, 0x00, 0x07, 0x80, 0x00, 0x00}, "No user")},
      {FoeError::BootstrapOnly, cat({0x05, 0x00, 0x08, 0x80, 0x00, 0x00}, "Bootstrap only")},
      {FoeError::NotBootstrap, cat({0x05, 0x00, 0x09, 0x80, 0x00, 0x00}, "Not Bootstrap")},
      {FoeError::NoRights, cat({0x05, 0x00, 0x0A, 0x80, 0x00, 0x00}, "No rights")},
      {FoeError::ProgramError, cat({0x05, 0x00, 0x0B, 0x80, 0x00, 0x00}, "Program Error")},
      {FoeError::WrongChecksum, cat({0x05, 0x00, 0x0C, 0x80, 0x00, 0x00}, "Wrong checksum")},
      {FoeError::FirmwareDoesNotFitHardware,
       cat({0x05, 0x00, 0x0D, 0x80, 0x00, 0x00}, "Firmware does not fit for hardware")},
      {FoeError::NoFileToRead, cat({0x05, 0x00, 0x0F, 0x80, 0x00, 0x00}, "No file to read")},
      {FoeError::FileHeaderDoesNotExist,
       cat({0x05, 0x00, 0x10, 0x80, 0x00, 0x00}, "File header does not exist")},
      {FoeError::FlashProblem, cat({0x05, 0x00, 0x11, 0x80, 0x00, 0x00}, "Flash problem")},
      {FoeError::FileIncompatible, cat({0x05, 0x00, 0x12, 0x80, 0x00, 0x00}, "File incompatible")},
  };
  for (const auto& g : table) {
    backend.begin_error = g.error;
    EXPECT_EQ(send(kWrqFileA, 64), g.reply) << static_cast<int>(g.error);
    EXPECT_TRUE(server.idle());
  }
}

TEST(FoeError, StandardTexts) {
  EXPECT_EQ(describe(FoeError::NotDefined), "Not defined");
  EXPECT_EQ(describe(FoeError::AlreadyExists), "Already exists");
  EXPECT_EQ(describe(FoeError::NoUser), "No user");
  EXPECT_EQ(describe(FoeError::BootstrapOnly), "Bootstrap only");
  EXPECT_EQ(describe(FoeError::NotBootstrap), "Not Bootstrap");
  EXPECT_EQ(describe(FoeError::ProgramError), "Program Error");
  EXPECT_EQ(describe(FoeError::NoFileToRead), "No file to read");
  EXPECT_EQ(describe(FoeError::FileHeaderDoesNotExist), "File header does not exist");
  EXPECT_EQ(describe(FoeError::FlashProblem), "Flash problem");
  EXPECT_EQ(describe(FoeError::FileIncompatible), "File incompatible");
  EXPECT_EQ(describe(static_cast<FoeError>(0x800E)), "Unknown FoE error");
}

}  // namespace
}  // namespace rackcat::foe
