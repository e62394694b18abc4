// A device built from its ESI (device/esi_device.hpp) behind the ecat::Application seam: it
// serves the SII image encoded from the ESI, answers CoE through coe::SdoServer when the ESI
// has a CoE mailbox, and exchanges process data per its PDOs. Outputs the master writes stay
// readable (outputs()); inputs are whatever set_inputs()/the line's wiring put there (with CoE,
// the mapped input objects, which SDO uploads show).
#pragma once

#include <atomic>
#include <functional>
#include <memory>
#include <mutex>
#include <span>
#include <vector>

#include "coe/process_image.hpp"
#include "coe/sdo_server.hpp"
#include "device/esi_device.hpp"
#include "ecat/application.hpp"
#include "ecat/slave/mailbox_protocol.hpp"
#include "foe/foe_server.hpp"

namespace rackcat::device {

class GenericDevice final : public ecat::Application {
 public:
  // The CoE protocol add_mailbox_protocols() registers (unit tests drive it directly).
  ecat::MailboxProtocol& coe_mailbox() { return coe_mailbox_; }
  explicit GenericDevice(EsiDevice esi);

  const EsiDevice& esi() const { return esi_; }
  coe::ObjectDictionary& dictionary() { return esi_.dictionary; }

  // Process-data sizes with the current assignment (SM2 outputs, SM3 inputs).
  ecat::ProcessDataSizes process_data_sizes() const override;
  // Last outputs the master wrote (SM2 bytes; zeros before the first write).
  std::vector<uint8_t> outputs() const;
  // Replace bits [bit, bit+bits) of the inputs (SM3 layout). Thread-safe.
  void set_input_bits(size_t bit, size_t bits, std::span<const uint8_t> source, size_t source_bit);
  std::vector<uint8_t> inputs() const;
  // Loopback wiring: each cycle, bits [from_bit, from_bit+bits) of `source`'s outputs become
  // bits [to_bit, ...) of this device's inputs. Call before the line runs.
  void add_wire(const GenericDevice& source, size_t from_bit, size_t to_bit, size_t bits);
  // Each cycle, bits [to_bit, to_bit+bits) (bits <= 64) of the inputs become the low bits of
  // `code()` (a signal source of the line). `code` runs on the cyclic path: it must not
  // allocate. Call before the line runs.
  void add_input_driver(size_t to_bit, size_t bits, std::function<uint64_t()> code);

  // Serves FoE (ETG.1000.6 §5.8) from `files` in every mailbox state and BOOT, when the ESI
  // announces it (<Mailbox><FoE/>, SII word 0x1C bit 3); without this call a FoE request gets
  // the mailbox error "unsupported protocol". `files` must outlive the device; call before the
  // line runs (add_mailbox_protocols).
  void serve_foe(foe::FileBackend& files, foe::FoeLimits limits = {});
  bool serves_foe() const { return foe_ != nullptr; }

  std::span<const uint8_t> eeprom() const override { return sii_; }
  uint16_t on_state_request(EsmState from, EsmState to) override;
  void on_state_changed(EsmState from, EsmState to) override;
  void add_mailbox_protocols(ecat::MailboxServer& server) override;
  bool mailbox_pending() const override {
    return (sdo_ && sdo_->has_pending()) || (foe_ && !foe_->idle());
  }
  bool update_inputs(std::span<uint8_t> inputs) override;
  void on_outputs(std::span<const uint8_t> outputs) override;
  void on_watchdog_expired() override;

 private:
  EsiDevice esi_;
  std::vector<uint8_t> sii_;
  std::unique_ptr<coe::SdoServer> sdo_;
  std::unique_ptr<coe::ProcessImage> image_;
  EsmState state_ = EsmState::Init;
  // The SDO server as the firmware's CoE mailbox protocol (ETG.1000.6 §5.6).
  struct CoeMailbox final : ecat::MailboxProtocol {
    explicit CoeMailbox(GenericDevice& d) : device(d) {}
    mailbox::Answer on_request(const ecat::MailboxRequest& request,
                               std::span<uint8_t> reply) override;
    size_t poll(std::span<uint8_t> reply) override;
    GenericDevice& device;
  };
  CoeMailbox coe_mailbox_{*this};
  std::unique_ptr<foe::FoeServer> foe_;
  // The FoE server as the firmware's FoE mailbox protocol.
  struct FoeMailbox final : ecat::MailboxProtocol {
    explicit FoeMailbox(GenericDevice& d) : device(d) {}
    mailbox::Answer on_request(const ecat::MailboxRequest& request,
                               std::span<uint8_t> reply) override;
    size_t poll(std::span<uint8_t> reply) override;
    GenericDevice& device;
  };
  FoeMailbox foe_mailbox_{*this};
  ecat::ProcessDataSizes sizes_;
  mutable std::mutex mutex_;  // guards outputs_/inputs_ against the control side
  std::vector<uint8_t> outputs_;
  std::vector<uint8_t> inputs_;
  struct Wire {
    const GenericDevice* source;
    size_t from_bit, to_bit, bits;
  };
  std::vector<Wire> wires_;
  struct Driver {
    size_t to_bit, bits;
    std::function<uint64_t()> code;
  };
  std::vector<Driver> drivers_;
};

// Copies bits between byte buffers (LSB-first, EtherCAT bit order).
void copy_bits(std::span<const uint8_t> src, size_t src_bit, std::span<uint8_t> dst, size_t dst_bit,
               size_t bits);

}  // namespace rackcat::device
