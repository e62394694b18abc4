#include "tests/ecat/test_application.hpp"

#include "base/round_time.hpp"
#include "ecat/slave/mailbox_server.hpp"

#include <algorithm>
#include <string_view>

namespace rackcat::ecat::test {

namespace {

void put16(std::vector<uint8_t>& v, size_t byte, uint16_t value) {
  v[byte] = static_cast<uint8_t>(value);
  v[byte + 1] = static_cast<uint8_t>(value >> 8);
}
void put32(std::vector<uint8_t>& v, size_t byte, uint32_t value) {
  put16(v, byte, static_cast<uint16_t>(value));
  put16(v, byte + 2, static_cast<uint16_t>(value >> 16));
}
void append16(std::vector<uint8_t>& v, uint16_t value) {
  v.push_back(static_cast<uint8_t>(value));
  v.push_back(static_cast<uint8_t>(value >> 8));
}
// ETG.2010 §2.3: category header {type, length in words}, then the data (padded to words).
void append_category(std::vector<uint8_t>& v, uint16_t type, std::vector<uint8_t> data) {
  if (data.size() % 2) data.push_back(0);
  append16(v, type);
  append16(v, static_cast<uint16_t>(data.size() / 2));
  v.insert(v.end(), data.begin(), data.end());
}
std::vector<uint8_t> sm_entry(uint16_t start, uint16_t len, uint8_t control, uint8_t type) {
  return {static_cast<uint8_t>(start),
          static_cast<uint8_t>(start >> 8),
          static_cast<uint8_t>(len),
          static_cast<uint8_t>(len >> 8),
          control,
          0x00,
          0x01,
          type};
}

}  // namespace

std::vector<uint8_t> make_test_sii() {
  std::vector<uint8_t> v(128, 0);
  // ESC configuration area (words 0-7): PDI control 0x05 (SPI, the PDI of a µC-based slave),
  // ESC configuration 0x00, PDI configuration 0, SYNC pulse length 1000 x 10 ns, alias 0.
  put16(v, 0x00, 0x0005);
  put16(v, 0x04, 0x03E8);
  // Word 7: CRC-8 (poly 0x07, init 0xFF) over bytes 0-13.
  uint8_t crc = 0xFF;
  for (int i = 0; i < 14; ++i) {
    crc ^= v[i];
    for (int b = 0; b < 8; ++b)
      crc = static_cast<uint8_t>((crc & 0x80) ? (crc << 1) ^ 0x07 : crc << 1);
  }
  v[14] = crc;
  put32(v, 0x08 * 2, kVendorId);
  put32(v, 0x0A * 2, kProductCode);
  put32(v, 0x0C * 2, kRevision);
  put32(v, 0x0E * 2, kSerial);
  // Words 0x14-0x17 bootstrap mailbox: none. Words 0x18-0x1B standard mailbox.
  put16(v, 0x18 * 2, kMbxOutStart);
  put16(v, 0x19 * 2, kMbxSize);
  put16(v, 0x1A * 2, kMbxInStart);
  put16(v, 0x1B * 2, kMbxSize);
  put16(v, 0x1C * 2, 0x0004);  // mailbox protocols: CoE
  put16(v, 0x3E * 2, 0x0001);  // EEPROM size: (1 + 1) Kbit = 256 bytes
  put16(v, 0x3F * 2, 0x0001);  // SII version 1
  // Category 10, strings: count, then length-prefixed strings.
  constexpr std::string_view kName = "rackcat test";
  std::vector<uint8_t> strings{1, static_cast<uint8_t>(kName.size())};
  strings.insert(strings.end(), kName.begin(), kName.end());
  append_category(v, 10, strings);
  // Category 30, general (32 bytes): name string index 1, CoE details SDO + SDO info + CA.
  std::vector<uint8_t> general(32, 0);
  general[3] = 1;
  general[5] = 0x01 | 0x02 | 0x20;
  append_category(v, 30, general);
  // Category 40, FMMU usage: outputs, inputs, SM status, unused.
  append_category(v, 40, {0x01, 0x02, 0x03, 0xFF});
  // Category 41, SyncManagers: mailbox out/in, process data out/in.
  std::vector<uint8_t> sms;
  for (const auto& e :
       {sm_entry(kMbxOutStart, kMbxSize, 0x26, 1), sm_entry(kMbxInStart, kMbxSize, 0x22, 2),
        sm_entry(kOutputsStart, kOutputBytes, 0x64, 3),
        sm_entry(kInputsStart, kInputBytes, 0x20, 4)}) {
    sms.insert(sms.end(), e.begin(), e.end());
  }
  append_category(v, 41, sms);
  append16(v, 0xFFFF);  // end
  return v;
}

TestApplication::TestApplication() : sii(make_test_sii()) {}

void TestApplication::on_eeprom_write(uint16_t word_address, std::span<const uint8_t> data) {
  eeprom_writes.emplace_back(word_address, static_cast<uint16_t>(data[0] | data[1] << 8));
}

uint16_t TestApplication::on_state_request(EsmState, EsmState to) {
  return (veto_code != 0 && to == veto_to) ? veto_code : 0;
}

void TestApplication::on_state_changed(EsmState from, EsmState to) {
  transitions.emplace_back(from, to);
}

void TestApplication::add_mailbox_protocols(MailboxServer& server) {
  server.add(mailbox::Type::CoE, *this);
}

mailbox::Answer TestApplication::on_request(const MailboxRequest& request,
                                            std::span<uint8_t> reply) {
  ++mailbox_requests;
  last_request.assign(request.data.begin(), request.data.end());
  // Echo: the request's mailbox data; the server frames it.
  const size_t n = std::min(request.data.size(), reply.size());
  std::copy_n(request.data.begin(), n, reply.begin());
  return {n, mailbox::Error::None};
}

size_t TestApplication::poll(std::span<uint8_t> reply) {
  ++polls;
  if (pending_emergency.empty() || pending_emergency.size() > reply.size()) return 0;
  std::copy(pending_emergency.begin(), pending_emergency.end(), reply.begin());
  const size_t n = pending_emergency.size();
  pending_emergency.clear();
  return n;
}

bool TestApplication::update_inputs(std::span<uint8_t> inputs) {
  ++inputs_count;
  inputs_time = base::RoundTime::now();
  if (!inputs_changed) return false;
  std::copy_n(inputs_value.begin(), std::min(inputs.size(), inputs_value.size()), inputs.begin());
  return true;
}

void TestApplication::on_outputs(std::span<const uint8_t> outputs) {
  ++outputs_count;
  last_outputs.assign(outputs.begin(), outputs.end());
}

void TestApplication::on_sync(int which, uint64_t system_time_ns) {
  syncs.emplace_back(which, system_time_ns);
}

}  // namespace rackcat::ecat::test
