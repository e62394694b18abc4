#include "tests/ecat/test_master.hpp"

#include <stdexcept>

#include "tests/ecat/test_application.hpp"
#include "tests/support/fmmu_entry.hpp"

namespace rackcat::ecat::test {

uint16_t get16(const std::vector<uint8_t>& v, size_t at) {
  return static_cast<uint16_t>(v.at(at) | v.at(at + 1) << 8);
}
uint32_t get32(const std::vector<uint8_t>& v, size_t at) {
  return get16(v, at) | static_cast<uint32_t>(get16(v, at + 2)) << 16;
}
uint64_t get64(const std::vector<uint8_t>& v, size_t at) {
  return get32(v, at) | static_cast<uint64_t>(get32(v, at + 4)) << 32;
}
std::vector<uint8_t> bytes16(uint16_t v) {
  return {static_cast<uint8_t>(v), static_cast<uint8_t>(v >> 8)};
}
std::vector<uint8_t> bytes32(uint32_t v) {
  auto a = bytes16(static_cast<uint16_t>(v));
  auto b = bytes16(static_cast<uint16_t>(v >> 16));
  a.insert(a.end(), b.begin(), b.end());
  return a;
}
std::vector<uint8_t> bytes64(uint64_t v) {
  auto a = bytes32(static_cast<uint32_t>(v));
  auto b = bytes32(static_cast<uint32_t>(v >> 32));
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

FrameBuilder& FrameBuilder::add(Command cmd, uint16_t adp, uint16_t ado, std::vector<uint8_t> data,
                                uint16_t wkc) {
  items_.push_back({static_cast<uint8_t>(cmd),
                    static_cast<uint32_t>(adp) | static_cast<uint32_t>(ado) << 16, std::move(data),
                    wkc});
  return *this;
}

FrameBuilder& FrameBuilder::add_logical(Command cmd, uint32_t address, std::vector<uint8_t> data) {
  items_.push_back({static_cast<uint8_t>(cmd), address, std::move(data), 0});
  return *this;
}

std::vector<uint8_t> FrameBuilder::build() const {
  std::vector<uint8_t> f = {0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0x00, 0x00,
                            0x00, 0x00, 0x00, 0x01, 0x88, 0xA4, 0,    0};
  size_t payload = 0;
  for (size_t i = 0; i < items_.size(); ++i) {
    const Item& it = items_[i];
    const uint16_t len =
        static_cast<uint16_t>(it.data.size() | (i + 1 < items_.size() ? 0x8000 : 0));
    f.push_back(it.cmd);
    f.push_back(static_cast<uint8_t>(0x40 + i));  // index
    for (int b = 0; b < 4; ++b) f.push_back(static_cast<uint8_t>(it.address >> (8 * b)));
    f.push_back(static_cast<uint8_t>(len));
    f.push_back(static_cast<uint8_t>(len >> 8));
    f.push_back(0);  // irq
    f.push_back(0);
    f.insert(f.end(), it.data.begin(), it.data.end());
    f.push_back(static_cast<uint8_t>(it.wkc));
    f.push_back(static_cast<uint8_t>(it.wkc >> 8));
    payload += 12 + it.data.size();
  }
  f[14] = static_cast<uint8_t>(payload);
  f[15] = static_cast<uint8_t>(0x10 | ((payload >> 8) & 0x07));
  if (f.size() < 60) f.resize(60, 0);
  return f;
}

std::vector<Reply> decode(const std::vector<uint8_t>& f) {
  std::vector<Reply> out;
  size_t pos = 16;
  while (true) {
    Reply r;
    r.command = f.at(pos);
    r.index = f.at(pos + 1);
    r.adp = get16(f, pos + 2);
    r.ado = get16(f, pos + 4);
    const uint16_t len = get16(f, pos + 6);
    r.irq = get16(f, pos + 8);
    r.data.assign(f.begin() + static_cast<long>(pos) + 10,
                  f.begin() + static_cast<long>(pos) + 10 + (len & 0x7FF));
    r.wkc = get16(f, pos + 10 + (len & 0x7FF));
    out.push_back(r);
    pos += 12 + (len & 0x7FF);
    if (!(len & 0x8000)) break;
  }
  return out;
}

std::vector<Reply> TestMaster::send_frame(const FrameBuilder& frame) {
  std::vector<uint8_t> f = frame.build();
  const size_t n = segment_.process(f);
  segment_.after_frame();  // the reply is back at the master; the firmware runs now
  if (n != f.size()) throw std::runtime_error("frame not returned at full length");
  return decode(f);
}

Reply TestMaster::send(Command cmd, uint16_t adp, uint16_t ado, std::vector<uint8_t> data) {
  FrameBuilder b;
  b.add(cmd, adp, ado, std::move(data));
  return send_frame(b).at(0);
}

Reply TestMaster::send_logical(Command cmd, uint32_t address, std::vector<uint8_t> data) {
  FrameBuilder b;
  b.add_logical(cmd, address, std::move(data));
  return send_frame(b).at(0);
}

uint16_t TestMaster::fpwr32(uint16_t station, uint16_t ado, uint32_t v) {
  return fpwr(station, ado, bytes32(v)).wkc;
}
uint16_t TestMaster::fpwr64(uint16_t station, uint16_t ado, uint64_t v) {
  return fpwr(station, ado, bytes64(v)).wkc;
}
uint16_t TestMaster::fprd16(uint16_t station, uint16_t ado) {
  return get16(fprd(station, ado, 2).data, 0);
}
uint32_t TestMaster::fprd32(uint16_t station, uint16_t ado) {
  return get32(fprd(station, ado, 4).data, 0);
}
uint64_t TestMaster::fprd64(uint16_t station, uint16_t ado) {
  return get64(fprd(station, ado, 8).data, 0);
}

uint16_t TestMaster::sii_read_word(uint16_t station, uint32_t word) {
  // SOEM: control (read command 0x0100) and address in one write, then poll, then data.
  std::vector<uint8_t> cmd = {0x00, 0x01};
  auto addr = bytes32(word);
  cmd.insert(cmd.end(), addr.begin(), addr.end());
  fpwr(station, 0x0502, cmd);
  return fprd16(station, 0x0508);
}

void TestMaster::config_init() {
  const uint16_t n = static_cast<uint16_t>(segment_.size());
  send(Command::Bwr, 0, 0x0103, {0x00});                       // 1: alias off
  send(Command::Bwr, 0, 0x0120, {0x11});                       // 2: INIT + ACK
  send(Command::Brd, 0, 0x0000, {0, 0});                       // 3: count slaves
  send(Command::Bwr, 0, 0x0101, {0x00});                       // 4: DL control loop ports
  send(Command::Bwr, 0, 0x0200, {0, 0});                       //    IRQ mask
  send(Command::Bwr, 0, 0x0300, std::vector<uint8_t>(8, 0));   // error counters
  send(Command::Bwr, 0, 0x0600, std::vector<uint8_t>(48, 0));  // FMMUs 0-2
  send(Command::Bwr, 0, 0x0800, std::vector<uint8_t>(32, 0));  // SMs 0-3
  send(Command::Bwr, 0, 0x0981, {0x00});                       // 5: DC activation off
  send(Command::Bwr, 0, 0x0910, std::vector<uint8_t>(4, 0));   //    DC system time
  send(Command::Bwr, 0, 0x0930, bytes16(0x1000));              //    speed counter start
  send(Command::Bwr, 0, 0x0934, bytes16(0x0C00));              //    filter depth
  send(Command::Bwr, 0, 0x0500, {0x02});                       // 6: EEPROM to master (force)
  send(Command::Bwr, 0, 0x0500, {0x00});
  for (uint16_t k = 0; k < n; ++k) {  // 7: station addresses
    const auto adp = static_cast<uint16_t>(0 - k);
    send(Command::Aprd, adp, 0x0140, {0, 0});
    send(Command::Apwr, adp, 0x0010, bytes16(static_cast<uint16_t>(0x1001 + k)));
    send(Command::Apwr, adp, 0x0100, {0x00});
    send(Command::Aprd, adp, 0x0010, {0, 0});
  }
  for (uint16_t k = 0; k < n; ++k) {
    const auto station = static_cast<uint16_t>(0x1001 + k);
    fprd(station, 0x0012, 2);  // 8: alias, SII status
    fprd(station, 0x0502, 2);
    for (uint32_t w : {0x08u, 0x0Au, 0x0Cu, 0x0Eu, 0x18u, 0x1Au, 0x1Cu})
      sii_read_word(station, w);  // 9
    fprd(station, 0x0008, 2);     // 10
    fprd(station, 0x0110, 2);
    fprd(station, 0x0007, 1);
    fprd(station, 0x0130, 6);
    // 11: SM0 and SM1 in one datagram, from SII words 0x18-0x1B.
    std::vector<uint8_t> sm;
    for (auto [start, len, ctrl] :
         {std::tuple{sii_read_word(station, 0x18), sii_read_word(station, 0x19), 0x26},
          std::tuple{sii_read_word(station, 0x1A), sii_read_word(station, 0x1B), 0x22}}) {
      auto s = bytes16(start);
      auto l = bytes16(len);
      sm.insert(sm.end(), s.begin(), s.end());
      sm.insert(sm.end(), l.begin(), l.end());
      sm.push_back(static_cast<uint8_t>(ctrl));
      sm.push_back(0x00);
      sm.push_back(0x01);
      sm.push_back(0x00);
    }
    fpwr(station, 0x0800, sm);
    fpwr8(station, 0x0500, 0x01);     // 12: EEPROM to PDI
    fpwr16(station, 0x0120, 0x0012);  // PREOP + ACK
  }
}

uint16_t TestMaster::request_state(uint16_t station, uint8_t state) {
  fpwr16(station, 0x0120, state);
  return fprd16(station, 0x0130);
}

void TestMaster::config_map() {
  uint32_t logical = logical_outputs_base;
  const uint16_t n = static_cast<uint16_t>(segment_.size());
  // Outputs of all slaves first, then inputs (SOEM's layout).
  std::vector<uint32_t> out_at(n), in_at(n);
  for (uint16_t k = 0; k < n; ++k) out_at[k] = logical + k * kOutputBytes;
  for (uint16_t k = 0; k < n; ++k) in_at[k] = logical + n * kOutputBytes + k * kInputBytes;
  for (uint16_t k = 0; k < n; ++k) {
    const auto station = static_cast<uint16_t>(0x1001 + k);
    std::vector<uint8_t> sm2 = {0x00, 0x11, kOutputBytes, 0x00, 0x64, 0x00, 0x01, 0x00};
    std::vector<uint8_t> sm3 = {0x80, 0x11, kInputBytes, 0x00, 0x20, 0x00, 0x01, 0x00};
    fpwr(station, 0x0810, sm2);
    fpwr(station, 0x0818, sm3);
    auto fmmu = [](uint32_t log, uint16_t len, uint16_t phys, uint8_t type) {
      return rackcat::testing::fmmu_entry(log, len, 0, 7, phys, 0, type);
    };
    fpwr(station, 0x0600, fmmu(out_at[k], kOutputBytes, kOutputsStart, 2));
    fpwr(station, 0x0610, fmmu(in_at[k], kInputBytes, kInputsStart, 1));
  }
}

std::vector<uint8_t> hex(std::string_view text, size_t pad_to) {
  std::vector<uint8_t> out;
  int nibbles = 0;
  uint8_t value = 0;
  for (char c : text) {
    int v = -1;
    if (c >= '0' && c <= '9') v = c - '0';
    if (c >= 'a' && c <= 'f') v = c - 'a' + 10;
    if (c >= 'A' && c <= 'F') v = c - 'A' + 10;
    if (v < 0) continue;
    value = static_cast<uint8_t>(value << 4 | v);
    if (++nibbles == 2) {
      out.push_back(value);
      nibbles = 0;
      value = 0;
    }
  }
  if (out.size() < pad_to) out.resize(pad_to, 0);
  return out;
}

Line::Line(size_t n, SegmentOptions options, const Clock* time) {
  std::vector<Application*> ptrs;
  for (size_t i = 0; i < n; ++i) {
    apps.push_back(std::make_unique<TestApplication>());
    ptrs.push_back(apps.back().get());
  }
  segment = std::make_unique<Segment>(ptrs, time != nullptr ? *time : clock, options);
  master = std::make_unique<TestMaster>(*segment);
}

void Line::to_safeop() {
  to_preop();
  master->config_map();
  for (size_t i = 0; i < apps.size(); ++i) master->request_state(station(i), 0x04);
}

void Line::to_op() {
  to_safeop();
  cycle(std::vector<uint8_t>(apps.size() * kOutputBytes, 0));
  for (size_t i = 0; i < apps.size(); ++i) master->request_state(station(i), 0x08);
}

std::vector<Reply> Line::cycle(const std::vector<uint8_t>& outputs) {
  std::vector<uint8_t> image = outputs;
  image.resize(apps.size() * (kOutputBytes + kInputBytes), 0);
  FrameBuilder b;
  b.add_logical(Command::Lrw, master->logical_outputs_base, image);
  b.add(Command::Frmw, station(0), 0x0910, std::vector<uint8_t>(8, 0));
  return master->send_frame(b);
}

}  // namespace rackcat::ecat::test
