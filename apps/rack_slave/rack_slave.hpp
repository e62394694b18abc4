// One emulated rack behind one emulated ESC: adapts the Fusion.IO-style device (mdp::Device,
// with its slot-card drivers, modules::Rack) to the ESC's application interface
// (ecat::Application). This is the only place where the ESC side and the device side meet;
// neither knows the other.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "ecat/application.hpp"
#include "ecat/slave/mailbox_protocol.hpp"
#include "mdp/device.hpp"
#include "mdp/rack_config.hpp"
#include "mdp/state_directory.hpp"
#include "modules/rack/rack.hpp"

namespace rackcat::apps {

class RackSlave final : public ecat::Application {
 public:
  // `position` (0-based) distinguishes the slaves of a segment: it is added to the serial
  // number (0x1018:04, SII word 0x0E) and names the slave's own state directory.
  RackSlave(mdp::RackConfig config, const std::string& state_dir, int position);
  // The same below an open state directory: slave 0 uses `state_dir` itself, slave N its
  // subdirectory "slave-N" (mdp::StateDirectory::child: never a symlink out of it).
  RackSlave(mdp::RackConfig config, const std::shared_ptr<mdp::StateDirectory>& state_dir,
            int position);
  ~RackSlave() override;

  mdp::Device& device() { return *device_; }
  // Called (on the ESC's thread) when the device reset command 0xFBF0 has been answered and
  // the master has read the answer: the owner restarts the ESC's application side
  // (ecat::Firmware::application_restart).
  void set_restart_handler(std::function<void()> fn) { restart_ = std::move(fn); }
  // The owner calls this after the current frame, before it restarts the firmware: the SII
  // image follows the firmware that runs now (its revision, SII word 0x0C). Building it takes
  // milliseconds, so it must not run inside a frame: SOEM drops a reply later than 2 ms and a
  // lost answer to the 0xFBF0 write would never be repeated after the restart.
  void finish_device_reset();
  modules::Rack& rack() { return *rack_; }
  // The mailbox protocols add_mailbox_protocols() registers (unit tests drive them directly).
  ecat::MailboxProtocol& coe_mailbox() { return coe_mailbox_; }
  ecat::MailboxProtocol& foe_mailbox() { return foe_mailbox_; }

  std::span<const uint8_t> eeprom() const override { return sii_; }
  uint16_t on_state_request(EsmState from, EsmState to) override;
  void on_state_changed(EsmState from, EsmState to) override;
  ecat::ProcessDataSizes process_data_sizes() const override;
  void add_mailbox_protocols(ecat::MailboxServer& server) override;
  bool mailbox_pending() const override;
  bool update_inputs(std::span<uint8_t> inputs) override;
  void on_outputs(std::span<const uint8_t> outputs) override;
  void on_sync(int which, uint64_t system_time_ns) override;
  void on_watchdog_expired() override;

 private:
  // Every frame reads these two (mailbox_pending, then the process data): in the object's
  // first line, the device's handle held in place rather than behind one more pointer (issue
  // 16: a line of slaves is bound by the cache lines each one touches per frame).
  std::optional<mdp::Device> device_;
  bool restart_pending_ = false;
  std::unique_ptr<modules::Rack> rack_;  // the slot cards; a CycleListener of device_
  std::vector<uint8_t> sii_;

  // The device's CoE server as the firmware's CoE mailbox protocol (ETG.1000.6 §5.6).
  struct CoeMailbox final : ecat::MailboxProtocol {
    explicit CoeMailbox(RackSlave& s) : slave(s) {}
    mailbox::Answer on_request(const ecat::MailboxRequest& request,
                               std::span<uint8_t> reply) override;
    size_t poll(std::span<uint8_t> reply) override;
    RackSlave& slave;
  };
  CoeMailbox coe_mailbox_{*this};
  // The device's FoE server (ETG.1000.5 §5.3) as the firmware's FoE protocol, in BOOT too.
  struct FoeMailbox final : ecat::MailboxProtocol {
    explicit FoeMailbox(RackSlave& s) : slave(s) {}
    mailbox::Answer on_request(const ecat::MailboxRequest& request,
                               std::span<uint8_t> reply) override;
    size_t poll(std::span<uint8_t> reply) override;
    RackSlave& slave;
  };
  FoeMailbox foe_mailbox_{*this};
  std::function<void()> restart_;
  bool sii_stale_ = false;  // 0xFBF0 ran; finish_device_reset() rebuilds the SII image

  // Hears the device reset command (0xFBF0) among the device's listeners.
  struct ResetListener final : mdp::CycleListener {
    explicit ResetListener(RackSlave& s) : slave(s) {}
    void on_device_reset(mdp::Device&, bool /*factory*/) override { slave.device_reset(); }
    RackSlave& slave;
  };
  ResetListener reset_listener_{*this};
  // 0xFBF0 ran: the ESC side restarts once the answer is read (finish_device_reset() then
  // rebuilds the SII image, outside the frame).
  void device_reset();
};

}  // namespace rackcat::apps
