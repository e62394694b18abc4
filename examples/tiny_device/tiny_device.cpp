// tiny_device: the smallest complete rackcat device. Its dictionary holds the identity
// (0x1000, 0x1008, 0x1018), one input object 0x6000 (a 16-bit counter that counts process-data
// cycles) mapped by the one TxPDO 0x1A00 assigned to SM3 (0x1C13), and the SM communication
// types 0x1C00 (ETG.1000.6 §5.6.7). The SII image is derived from that dictionary
// (esi::describe_dictionary), so a master sees the same PDO over the SII and over CoE.
//
//   tiny_device --iface IFACE    answer EtherCAT frames on IFACE (needs CAP_NET_RAW)
#include <cstdio>
#include <cstring>
#include <span>
#include <string>
#include <vector>

#include "coe/access.hpp"
#include "coe/data_type.hpp"
#include "coe/object_dictionary.hpp"
#include "coe/sdo_server.hpp"
#include "ecat/application.hpp"
#include "ecat/host/runner.hpp"
#include "ecat/segment.hpp"
#include "ecat/slave/mailbox_server.hpp"
#include "esi/describe_dictionary.hpp"
#include "esi/sii_image.hpp"

namespace {

using namespace rackcat;

std::vector<uint8_t> le32(uint32_t v) {
  return {static_cast<uint8_t>(v), static_cast<uint8_t>(v >> 8), static_cast<uint8_t>(v >> 16),
          static_cast<uint8_t>(v >> 24)};
}

coe::Object var(uint16_t index, std::string name, coe::DataType type, uint16_t bits,
                uint16_t access, std::vector<uint8_t> value = {}) {
  coe::Object o(index, coe::ObjectCode::Var, name, static_cast<uint16_t>(type));
  o.add(coe::make_entry(0, std::move(name), type, bits, access, std::move(value)));
  return o;
}

// A RECORD/ARRAY whose subindex 0 counts the u32 entries that follow.
coe::Object list(uint16_t index, const std::string& name, coe::ObjectCode code, coe::DataType type,
                 uint16_t bits, const std::vector<uint32_t>& values) {
  coe::Object o(index, code, name, static_cast<uint16_t>(type));
  o.add(coe::make_entry(0, "Number of entries", coe::DataType::Unsigned8, 8, coe::access::kRo,
                        {static_cast<uint8_t>(values.size())}));
  for (size_t i = 0; i < values.size(); ++i) {
    std::vector<uint8_t> v = le32(values[i]);
    v.resize(bits / 8);
    o.add(coe::make_entry(static_cast<uint8_t>(i + 1), "Entry " + std::to_string(i + 1), type, bits,
                          coe::access::kRo, v));
  }
  return o;
}

coe::ObjectDictionary build_dictionary() {
  using coe::DataType;
  namespace acc = coe::access;
  coe::ObjectDictionary od;
  od.add(var(0x1000, "Device type", DataType::Unsigned32, 32, acc::kRo, le32(0)));
  const std::string name = "rackcat tiny device";
  od.add(var(0x1008, "Device name", DataType::VisibleString, static_cast<uint16_t>(8 * name.size()),
             acc::kRo, std::vector<uint8_t>(name.begin(), name.end())));
  // Identity (0x1018:01..04). Vendor ID 0 is not an ETG-assigned ID: set your own.
  coe::Object id = list(0x1018, "Identity", coe::ObjectCode::Record, DataType::Unsigned32, 32,
                        {0x00000000, 0x00007141, 0x00000001, 0x00000001});
  od.add(std::move(id));
  od.add(var(0x6000, "Counter", DataType::Unsigned16, 16, acc::kRo | acc::kTxPdoMappable, {0, 0}));
  // TxPDO 0x1A00: one entry, 0x6000:00, 16 bits (ETG.1000.6 Table 75 mapping format).
  od.add(list(0x1A00, "TxPDO", coe::ObjectCode::Record, DataType::Unsigned32, 32, {0x60000010}));
  // SM types: mailbox out, mailbox in, outputs, inputs (ETG.1000.6 Table 67).
  od.add(list(0x1C00, "Sync manager type", coe::ObjectCode::Array, DataType::Unsigned8, 8,
              {1, 2, 3, 4}));
  od.add(list(0x1C12, "RxPDO assign", coe::ObjectCode::Array, DataType::Unsigned16, 16, {}));
  od.add(list(0x1C13, "TxPDO assign", coe::ObjectCode::Array, DataType::Unsigned16, 16, {0x1A00}));
  return od;
}

// The device and its CoE mailbox protocol in one (the firmware dispatches CoE messages here).
class TinyDevice final : public ecat::Application, public ecat::MailboxProtocol {
 public:
  TinyDevice() : od_(build_dictionary()), sdo_(od_) {
    esi::DeviceTexts texts;
    texts.vendor_name = "rackcat example";
    texts.order_code = "tiny-device";
    texts.group_type = "rackcat";
    texts.group_name = "rackcat examples";
    sii_ = esi::encode_sii(esi::describe_dictionary(od_, texts, esi::SmPlan{})).bytes;
  }

  std::span<const uint8_t> eeprom() const override { return sii_; }
  uint16_t on_state_request(EsmState, EsmState) override { return 0; }
  void on_state_changed(EsmState, EsmState to) override { state_ = to; }
  ecat::ProcessDataSizes process_data_sizes() const override { return {.outputs = 0, .inputs = 2}; }
  void add_mailbox_protocols(ecat::MailboxServer& server) override {
    server.add(mailbox::Type::CoE, *this);
  }
  mailbox::Answer on_request(const ecat::MailboxRequest& request,
                             std::span<uint8_t> reply) override {
    return sdo_.handle(request.data, reply, request.state);
  }
  size_t poll(std::span<uint8_t> reply) override { return sdo_.poll(reply); }
  bool update_inputs(std::span<uint8_t> inputs) override {
    ++counter_;
    od_.find(0x6000)->set_u(0, counter_);
    if (inputs.size() >= 2) {
      inputs[0] = static_cast<uint8_t>(counter_);
      inputs[1] = static_cast<uint8_t>(counter_ >> 8);
    }
    return true;
  }
  void on_outputs(std::span<const uint8_t>) override {}

 private:
  coe::ObjectDictionary od_;
  coe::SdoServer sdo_;
  std::vector<uint8_t> sii_;
  EsmState state_ = EsmState::Init;
  uint16_t counter_ = 0;
};

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3 || std::strcmp(argv[1], "--iface") != 0) {
    std::fprintf(stderr, "usage: tiny_device --iface IFACE\n");
    return 2;
  }
  TinyDevice device;
  ecat::Runner runner({.interface_name = argv[2]});
  if (const int rc = runner.open("tiny_device"); rc != 0) return rc;
  std::vector<ecat::Application*> line{&device};
  ecat::Segment segment(line);
  std::printf("tiny_device: on %s\n", argv[2]);
  std::fflush(stdout);
  return runner.run(segment);
}
