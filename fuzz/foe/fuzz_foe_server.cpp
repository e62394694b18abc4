// Feeds FoE requests to one FoE server over an in-memory file backend. Input: byte 0 = receive
// mailbox data size - 7 (7..262), byte 1 = send mailbox data size - 7, byte 2 bit 0 = commits
// answer Busy once and reads are deferred once (FoeServer::poll sends their first reply), then
// requests as [length byte][bytes] (FoE header and data, ETG.1000.6 §5.8). Checks every reply: it
// fits the send mailbox, is one of the slave's OpCodes (Data, Ack, Error, Busy), and an Error
// carries a code of the 0x8000 range.
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

#include "foe/foe_server.hpp"

namespace {

using namespace rackcat::foe;

class Backend : public FileBackend {
 public:
  bool busy_once = false;
  std::map<std::string, std::vector<uint8_t>> files{{"fileA", std::vector<uint8_t>(300, 7)},
                                                    {"empty", {}}};
  std::string open;
  std::vector<uint8_t> pending;
  int busy = 0;

  std::string reading;
  size_t read_max = 0;
  int read_busy = 0;

  ReadProgress read_file(std::string_view name, uint32_t password, size_t max,
                         std::vector<uint8_t>& out) override {
    if (password == 1) return {false, FoeError::NoRights};
    reading = std::string(name);
    read_max = max;
    read_busy = busy_once ? 1 : 0;
    return poll_read(out);
  }
  ReadProgress poll_read(std::vector<uint8_t>& out) override {
    if (read_busy > 0) {
      --read_busy;
      return {true, FoeError::None};
    }
    auto it = files.find(reading);
    if (it == files.end()) return {false, FoeError::NotFound};
    if (it->second.size() > read_max) return {false, FoeError::DiskFull};
    out = it->second;
    return {false, FoeError::None};
  }
  void abort_read() override { reading.clear(); }
  FoeError begin_write(std::string_view name, uint32_t password) override {
    if (password == 1) return FoeError::NoRights;
    open = std::string(name);
    pending.clear();
    busy = busy_once ? 1 : 0;
    return FoeError::None;
  }
  FoeError write_data(std::span<const uint8_t> d) override {
    if (pending.size() + d.size() > 4096) return FoeError::DiskFull;
    pending.insert(pending.end(), d.begin(), d.end());
    return FoeError::None;
  }
  CommitProgress commit() override { return poll_commit(); }
  CommitProgress poll_commit() override {
    if (busy > 0) {
      --busy;
      return {true, FoeError::None, 0, 1};
    }
    if (!pending.empty() && pending[0] == 0xEE) return {false, FoeError::WrongChecksum, 1, 1};
    files[open] = pending;
    return {false, FoeError::None, 1, 1};
  }
  void abort_write() override { pending.clear(); }
};

// Every reply fits the send mailbox and is one the slave may send.
void check_reply(size_t length, const std::vector<uint8_t>& reply) {
  if (length == 0) return;
  if (length > reply.size() || length < FoeHeader::kSize) std::abort();
  const auto h = FoeHeader::decode(reply);
  switch (static_cast<OpCode>(h->opcode)) {
    case OpCode::Data:
    case OpCode::Ack:
    case OpCode::Busy:
      break;
    case OpCode::Error:
      if (h->value < 0x8000 || h->value > 0x8012) std::abort();
      break;
    default:
      std::abort();
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 3) return 0;
  Backend backend;
  backend.busy_once = data[2] & 1;
  uint64_t now = 0;
  FoeServer server(backend, FoeLimits{32, 2048, 1000}, [&now] { return now; });
  const size_t capacity = 7 + data[0];
  std::vector<uint8_t> reply(7 + data[1]);
  size_t pos = 3;
  while (pos < size) {
    const size_t len = std::min<size_t>(data[pos], size - pos - 1);
    const std::span<const uint8_t> request(data + pos + 1, std::min(len, capacity));
    pos += 1 + len;
    now += 100;
    const auto r = server.handle(request, capacity, reply);
    if (r.too_short && (r.length != 0 || request.size() >= FoeHeader::kSize)) std::abort();
    check_reply(r.length, reply);
    // The mailbox poll (a deferred read's first reply, timeouts, a commit's end).
    check_reply(server.poll(reply), reply);
  }
  return 0;
}
