// The Fusion.IO-style modular device (ETG.5001 MDP): the rack configuration, the object
// dictionary of the guide's Appendix A built from it, the CoE SDO server, the process image of
// the current PDO assignment (0x1C12/0x1C13), the command objects 0xFBF0..0xFBF4 and the stored
// parameters. apps/ adapts it to ecat::Application; modules/ attaches slot-card drivers to it as
// CycleListeners and reads/writes the 0x6nnX/0x7nnX/0x2rr1/0xF3xx objects through dictionary().
//
// Threading: every method runs on the one thread that drives the ESC (cyclic and mailbox path
// alike); listeners are called on that thread.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>

#include "base/background_worker.hpp"
#include "base/mailbox_error.hpp"
#include "coe/access.hpp"
#include "coe/diagnosis_history.hpp"
#include "coe/object_dictionary.hpp"
#include "mdp/device_runtime.hpp"
#include "mdp/rack_config.hpp"

namespace rackcat::mdp {

class Device;

// Slot-card drivers and other device behaviour plug in here. Callbacks on the cyclic path
// (on_outputs, before_inputs, on_sync) must not allocate or block.
class CycleListener {
 public:
  virtual ~CycleListener() = default;
  // SM2 data has just been unpacked into the mapped 0x7nnX entries.
  virtual void on_outputs(Device&) {}
  // Refresh the 0x6nnX objects (and other TxPDO-mappable entries) before they are packed
  // into the SM3 buffer.
  virtual void before_inputs(Device&) {}
  // Whether a cycle with the same output data as the last one would change no input and no
  // object of this listener's (mdp/repeated_cycles.hpp): asked after a full cycle, to let the
  // device skip the next repeated ones, and before each repeated one (a timer of the
  // listener's may be due). Whatever changes the listener from outside the cycle must call
  // Device::disturb(). The default, false, runs every cycle in full.
  virtual bool repeats_cycle() const { return false; }
  // After the ESM changed state (accepted request, error fallback, watchdog): leaving OP is
  // where outputs go to their safe state (0x4nn0..0x4nn3).
  virtual void on_state_changed(Device&, EsmState /*from*/, EsmState /*to*/) {}
  // SYNC0/SYNC1 from the distributed clock (ETG.1000.4 §6.8.3).
  virtual void on_sync(Device&, int /*which*/, uint64_t /*system_time_ns*/) {}
  // SM2 watchdog expired (the ESM goes to SAFEOP with AL status 0x001B).
  virtual void on_watchdog_expired(Device&) {}
  // 0xFBF1 executed: latched objects (0xF39x, latched 0x2rr1:08 bits) were cleared; set again
  // whatever cause is still active.
  virtual void on_exception_reset(Device&) {}
  // 0xF002 Detect Modules command executed.
  virtual void on_detect_modules(Device&) {}
  // Parameters were (re)loaded: start-up, 0xFBF4 reload, 0xFBF0 reset.
  virtual void on_parameters_loaded(Device&) {}
  // 0xFBF0 executed (from the SDO write, before its response): every object is back at its power-on
  // value with the stored parameters applied (factory: stored parameters deleted first). A real
  // device also resets its ESC; the application adapter does that here (ETG.5003.1).
  virtual void on_device_reset(Device&, bool /*factory*/) {}
};

class StateDirectory;

struct DeviceOptions {
  // Where 0xFBF2 stores parameters: an open state directory (state_directory.hpp), else the
  // directory `state_dir` (empty = default_state_dir()), opened with the caller's rights.
  std::shared_ptr<StateDirectory> state;
  std::string state_dir;
  // Load the stored parameter file at construction (a corrupt or foreign file is reported
  // through load_report() and ignored).
  bool load_stored_parameters = true;
  // Where the file work of the command objects and of the FoE files runs (one queue per
  // device, in order): nullptr = the process-wide base::BackgroundWorker::shared().
  base::BackgroundWorker* worker = nullptr;
};

// $XDG_STATE_HOME/rackcat, else $HOME/.local/state/rackcat.
std::string default_state_dir();

class Device {
 public:
  explicit Device(RackConfig config, DeviceOptions options = {});
  ~Device();
  Device(const Device&) = delete;
  Device& operator=(const Device&) = delete;

  const RackConfig& config() const;
  coe::ObjectDictionary& dictionary();
  const coe::ObjectDictionary& dictionary() const;
  // Modules numbered RIM by RIM, slot by slot; module.index(0x6000, kind) etc. give the
  // object indices of each module (ETG.5001 index distance 0x10).
  std::span<const Module> modules() const;

  // --- Mailbox protocols. The firmware's MailboxServer (ecat/slave) owns the mailbox frame
  // (ETG.1000.4 §5.6: header, counter, double writes, error replies); these take one request's
  // mailbox data and write the reply's data (SM1 after the header), answering its length
  // (0 = no reply) or a mailbox error for the server to send.
  // CoE (ETG.1000.6 §5.6) in the device's current state.
  mailbox::Answer coe_request(std::span<const uint8_t> request, std::span<uint8_t> reply);
  // Unsolicited CoE messages (Emergency, SDO Information fragments) when SM1 is free; 0 when
  // nothing is pending. Also where command objects whose file work has finished on the worker
  // (0xFBF0, 0xFBF2..0xFBF4) complete, so call it regularly (the firmware does, whenever the
  // mailbox is idle).
  size_t coe_poll(std::span<uint8_t> reply);
  // FoE (ETG.1000.5 §5.3), in BOOT too. `capacity`: the data bytes SM0 holds, which sets the
  // last-packet rule of writes.
  mailbox::Answer foe_request(std::span<const uint8_t> request, size_t capacity,
                              std::span<uint8_t> reply);
  // Drops an FoE transfer idle past its timeout, drives a finished commit to its end, and
  // sends the deferred first Data of a parameters.bin read once the worker has read the file
  // (its length; 0 = nothing to send). `reply` as for foe_request. Call whenever SM1 is free.
  size_t foe_poll(std::span<uint8_t> reply);
  // Whether coe_poll() or foe_poll() has work: an Emergency or SDO Information fragment
  // queued, a command's file work finished on the worker, a FoE transfer open (its timeout).
  // The firmware runs without an ESC event only then (ecat::Application::mailbox_pending).
  bool mailbox_pending() const;
  // Queue a CoE Emergency (ETG.1000.6 §5.6.4): error code (CiA-style, e.g. 0x4210), error
  // register (0x1001 style bits) and 5 manufacturer bytes ([0] RIM, [1] module, [2] event bit,
  // [3..4] channel mask). It is a diagnosis message like report_diagnosis() (text ID from
  // diag::text_for_emergency): stored in 0x10F3 unless filtered, and sent only when stored
  // and 0x10F3:05 bit 0 is set, so the Emergencies and the history never disagree (ETG.1020
  // ch. 13). Device thread. False when the Emergency queue is full.
  bool raise_emergency(uint16_t error_code, uint8_t error_register,
                       std::array<uint8_t, 5> data = {});

  // --- Diagnosis history 0x10F3 (ETG.1020 ch. 13, mdp/diagnosis_catalogue.hpp). Device thread,
  // no allocation. The message takes its type, Emergency code and register from the catalogue
  // entry of `text_id`, its time stamp from diagnosis_time().
  struct DiagnosisReport {
    uint16_t text_id = 0;
    uint8_t rim = 0;         // 0 = control module
    uint16_t module = 0;     // 0 = none
    uint8_t channel = 0xFF;  // 0-based, 0xFF = none
    uint16_t detail = 0;
  };
  coe::diag::AddResult report_diagnosis(const DiagnosisReport& report);
  const coe::diag::History& diagnosis() const;
  // What a master's write of 0xFBF1 does (guide, Exception Reset Command): clears the latched
  // exception objects and tells the listeners. Device thread (the control API's clear button).
  void reset_exceptions();
  // The DC system time (ns since 2000-01-01) extrapolated from the last SYNC0 while SYNC0 runs
  // (an event within the last second); otherwise ns since power-on and `local` = true.
  uint64_t diagnosis_time(bool& local) const;

  // --- Module enumeration (mdp/module_enumeration.hpp): `present[i]` != 0 enumerates module
  // i + 1. 0xF050, 0x3000, the default 0xF030 and the default 0x1C12/0x1C13 follow; the process
  // image is recompiled. The rack calls it at start, on 0xF002 and on 0xFBF0 (Detect Modules
  // Override 0: the modules of the online RIMs; 1: all). Mailbox path, not cyclic.
  void enumerate_modules(std::span<const uint8_t> present);

  // --- ESM (ETG.1000.6 §5.3). request_state returns 0 to accept or an AL status code:
  // 0x0070 when PREOP->SAFEOP finds the configured module list 0xF030 different from the
  // detected list 0xF050 (ETG.5001.1). SM size checks (0x001D/0x001E) are the ESC's.
  uint16_t request_state(EsmState from, EsmState to);
  void state_changed(EsmState from, EsmState to);
  EsmState state() const;

  // --- Process data for the current 0x1C12/0x1C13 assignment (fixed once SAFEOP is reached).
  uint16_t output_bytes() const;  // SM2 size
  uint16_t input_bytes() const;   // SM3 size
  // Cyclic path, no allocation: unpack SM2 into the mapped objects then call on_outputs();
  // call before_inputs() then pack the mapped objects into SM3. Shorter spans copy what fits.
  // A cycle that repeats the last one is skipped (mdp/repeated_cycles.hpp): write_outputs
  // leaves everything as it is, and read_inputs answers false with `sm3` untouched, which
  // then holds what the last full cycle packed. true: `sm3` was packed.
  void write_outputs(std::span<const uint8_t> sm2);
  bool read_inputs(std::span<uint8_t> sm3);
  // Something outside the cyclic exchange (a control command, a RIM link, a test) is about to
  // read or change the device or its listeners: the next cycle runs in full. The device's own
  // entry points (mailbox, ESM, SYNC, watchdog, the mutable dictionary()) call it themselves.
  void disturb();
  void sync_event(int which, uint64_t system_time_ns);
  void watchdog_expired();
  SyncStatistics& sync_statistics(bool outputs);  // 0x1C32 (true) / 0x1C33 (false)

  // What a listener hears: every callback, or all but the cyclic ones (on_outputs,
  // before_inputs, on_sync), which then do not visit it at all (issue 16: in a line of devices
  // every listener the cyclic path calls costs each device a cache line per frame).
  enum class ListenerScope : uint8_t { All, EventsOnly };
  void add_listener(CycleListener* listener, ListenerScope scope = ListenerScope::All);
  void remove_listener(CycleListener* listener);

  // --- Stored parameters (0xFBF2 store, 0xFBF4 load, 0xFBF0 factory reset).
  const std::string& state_dir() const;
  std::string parameter_file() const;
  // One line describing what happened to the stored file at the last load ("loaded 12
  // parameters from ...", "ignored corrupt parameter file ...: reason", "no stored parameters").
  const std::string& load_report() const;
  // What runs: "firmware 1.09.6 (revision 0x00010009, built in)" or the installed file's.
  const std::string& firmware_report() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace rackcat::mdp
