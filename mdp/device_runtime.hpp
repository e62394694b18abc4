// What the behaviour of an object asks of the running device. Each mdp/objects_*.cpp declares
// its objects (add_*_objects) and, next to them, what they do once a device runs
// (attach_*_behaviour: hooks on read and write); mdp::Device implements this interface for
// them. Everything here runs on the device thread, from the SDO server's hooks.
#pragma once

#include <chrono>
#include <cstdint>

namespace rackcat::mdp {

// Counters and flags of 0x1C32/0x1C33 the ESC side feeds (ETG.1020 §8 "SyncManager
// parameter"): the device counts per cycle, the master reads them by SDO.
struct SyncStatistics {
  uint16_t sm_event_missed = 0;       // 0x1C3x:0B
  uint16_t cycle_time_too_small = 0;  // 0x1C3x:0C
  bool sync_error = false;            // 0x1C3x:20
};

class DeviceRuntime {
 public:
  virtual ~DeviceRuntime() = default;

  // 0x2000:08 Clock: seconds the written clock is ahead of the system clock.
  virtual int64_t clock_offset_s() const = 0;
  virtual void set_clock_offset_s(int64_t offset) = 0;
  // 0x1C12/0x1C13 and the user PDOs changed: the process image follows.
  virtual void recompile_process_image() = 0;
  // 0x1C32 (true) / 0x1C33 (false).
  virtual SyncStatistics& sync_statistics(bool outputs) = 0;
  // 0xF9F6 Time since power on.
  virtual std::chrono::steady_clock::time_point power_on_time() const = 0;
  // 0xF002 Detect Modules: every configured module enumerated, then the drivers narrow it.
  virtual void detect_modules() = 0;

  // Command objects 0xFBF0..0xFBF4 (ETG.5003.1): the file work runs on the device's worker;
  // complete_commands() writes the status of what has finished.
  virtual void start_device_reset(bool factory) = 0;
  virtual void reset_exceptions() = 0;
  virtual void start_store() = 0;
  virtual void start_checksum(uint8_t algorithm) = 0;
  virtual void start_load() = 0;
  virtual void complete_commands() = 0;
};

}  // namespace rackcat::mdp
