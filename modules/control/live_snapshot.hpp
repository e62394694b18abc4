// What the web page streams (GET /api/stream, server-sent events): every slave's ESM and link
// state, the rack's RIMs, fans, temperatures, exception summary and every channel's value.
//
// Cost to the device thread: capture() is posted through the control API's command path and
// runs between two cycles; it only copies numbers into buffers sized when the snapshot was
// made (no allocation, no formatting, no lock of its own). The JSON is written afterwards on
// the API's worker thread by to_json().
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "modules/rack/rack.hpp"

namespace rackcat::modules {

// The ESC side of one slave (filled by the owner of the ESCs, apps/cmd_run.cpp), registers
// as ETG.1000.4 §6 names them.
struct SlaveLink {
  uint16_t position = 0;             // in the line (0 = first after the master)
  uint16_t station_address = 0;      // 0x0010
  uint8_t al_status = 0;             // 0x0130 (state | 0x10 error flag)
  uint16_t al_status_code = 0;       // 0x0134
  const char* al_status_text = "";   // ETG.1000.6 Table 11 name of the code (static text)
  bool pd_watchdog_running = false;  // 0x0440 bit 0: process data watchdog not expired
  uint8_t pd_watchdog_expiries = 0;  // 0x0442 watchdog counter process data
  uint32_t rx_errors = 0;            // 0x0300..0x030D: sum of the port and PU error counters
  uint64_t frames = 0;               // EtherCAT frames the device thread has processed
  uint32_t vendor_id = 0, product_code = 0, revision = 0;  // SII words 0x0008..0x000D
};
// Device thread; must not allocate.
using SlaveLinkFn = std::function<void(size_t slave, SlaveLink& out)>;

class LiveSnapshot {
 public:
  // Sizes every buffer for the slaves of a line: racks[i] is slave i's rack, or null for a
  // device that is not a rack (only its link is shown). Worker thread.
  explicit LiveSnapshot(const std::vector<Rack*>& racks);

  // Device thread, between cycles: copies the current values. No allocation.
  void capture(const std::vector<Rack*>& racks, const SlaveLinkFn& link);
  // Worker thread: the snapshot as one line of JSON (docs/WEB.md "Stream").
  std::string to_json() const;

 private:
  struct Rim {
    uint8_t number = 0;
    RimState state = RimState::Online;
    bool comm_error = false;
    double power_supply_rpm = 0, slot_card_rpm = 0;
    uint32_t event_status = 0;
  };
  struct Module {
    uint16_t number = 0;
    std::vector<double> inputs;
    std::vector<uint8_t> input_open;
    std::vector<double> commanded, driven, wire;
  };
  struct Slave {
    bool rack = false;
    SlaveLink link;
    EsmState esm = EsmState::Init;
    bool outputs_valid = false;
    double cpu_fan_rpm = 0, cpu_temperature = 0;
    uint32_t summary_active = 0, summary_latched = 0, device_event_status = 0;
    uint32_t diagnosis_messages = 0, diagnosis_newest = 0;
    std::vector<Rim> rims;
    std::vector<Module> modules;
  };
  std::vector<Slave> slaves_;
  double time_s_ = 0;
  uint64_t sequence_ = 0;
};

}  // namespace rackcat::modules
