// mdp::Device: the object dictionary of the rack behind the CoE SDO server, the process images of
// the PDO assignment, the ESM hooks, and the command objects (ETG.5003.1 0xFBF0..0xFBF4, ETG.5001
// 0xF002) with the stored parameters.
#include "mdp/device.hpp"

#include <algorithm>
#include <atomic>
#include <bit>
#include <cerrno>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <utility>

#include "base/round_time.hpp"
#include "coe/bits.hpp"
#include "coe/entry_slot.hpp"
#include "coe/process_image.hpp"
#include "coe/sdo_server.hpp"
#include "foe/foe_server.hpp"
#include "mdp/command_bytes.hpp"
#include "mdp/diagnosis_catalogue.hpp"
#include "mdp/file_access.hpp"
#include "mdp/firmware_image.hpp"
#include "mdp/firmware_store.hpp"
#include "mdp/firmware_version.hpp"
#include "mdp/module_enumeration.hpp"
#include "mdp/object_dictionary_builder.hpp"
#include "mdp/parameter_set.hpp"
#include "mdp/parameter_store.hpp"
#include "mdp/parameter_writer.hpp"
#include "mdp/repeated_cycles.hpp"
#include "mdp/state_directory.hpp"

namespace rackcat::mdp {

using coe::AbortCode;
using coe::Object;

std::string default_state_dir() {
  if (const char* xdg = std::getenv("XDG_STATE_HOME"); xdg && *xdg) {
    return std::string(xdg) + "/rackcat";
  }
  if (const char* home = std::getenv("HOME"); home && *home) {
    return std::string(home) + "/.local/state/rackcat";
  }
  return "rackcat-state";
}

namespace {

// ETG.1000.6 / ETG.5001.1: AL status code "invalid configuration" family; 0x0070 = module ident
// list mismatch (the configured 0xF030 differs from the detected 0xF050).
constexpr uint16_t kAlModuleIdentMismatch = 0x0070;
constexpr uint16_t kAlInvalidOutputConfig = 0x001D;
constexpr uint16_t kAlInvalidInputConfig = 0x001E;

}  // namespace

// On a cache line boundary: its first line holds what every cycle reads (issue 16).
struct alignas(64) Device::Impl final : DeviceRuntime {
  Impl() = default;
  // A reset job queued on the worker writes reset_firmware (a member destroyed before the
  // writer): finish every queued job before any member goes (shutdown only, not the device
  // thread's cycle).
  ~Impl() override {
    if (writer) writer->wait_idle();
  }
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;
  Device* self = nullptr;
  // mailbox_pending()'s O(1) answer (issue 16: asked for every slave on every frame): false
  // only while nothing can have become pending since the full check found nothing. Raised by
  // everything that can make the CoE/FoE side pending: a CoE or FoE request, an Emergency, a
  // state change, and the worker publishing a command's result (ParameterWriter::
  // notify_results). Starts raised.
  mutable std::atomic<bool> mailbox_hint{true};
  void raise_mailbox_hint() {
    std::atomic_thread_fence(std::memory_order_seq_cst);
    mailbox_hint.store(true, std::memory_order_seq_cst);
  }
  // --- What write_outputs/read_inputs touch, side by side (issue 16: the cyclic path of a
  // line of devices is bound by cache misses, not instructions).
  // A cycle that repeats the last one is skipped (mdp/repeated_cycles.hpp): on the first line,
  // with the vtable pointer, `self` and the mailbox hint that every frame reads.
  RepeatedCycles repeats;
  // A skipped cycle still latches the inputs (0xF6F0, not mapped when cycles repeat): its time
  // goes into the objects when anything outside the cycle next looks (disturb(), dictionary()),
  // since nothing can read them before that.
  bool latch_pending = false;
  base::RoundTime::Clock::time_point latch_at{};
  void disturb() {
    repeats.disturb();
    flush_latch();
  }
  void flush_latch() {
    if (!latch_pending) return;
    latch_pending = false;
    set_array(latch_local_slots, uptime_us(latch_at));
  }
  bool listeners_repeat() const {
    for (const CycleListener* l : cycle_listeners) {
      if (!l->repeats_cycle()) return false;
    }
    return true;
  }
  // The listeners of the cyclic callbacks (ListenerScope::All), a subset of `listeners`.
  std::vector<CycleListener*> cycle_listeners;
  // 0xF6F0/0xF6F2 (input latch times): their entries' slots, found once when the dictionary is
  // built, so the cyclic path does no dictionary or entry lookup.
  std::vector<coe::EntrySlot> latch_local_slots, latch_esc_slots;
  uint64_t last_sync_ns = 0;
  // 0xF6F2 changes only with SYNC0: what its entries hold, so a round without a new SYNC0
  // leaves the array (and its cache lines) alone. Stale until written, and again whenever the
  // dictionary is reloaded (power_on_reset).
  uint64_t latch_esc_value = 0;
  bool latch_esc_stale = true;
  std::chrono::steady_clock::time_point power_on = std::chrono::steady_clock::now();
  std::optional<coe::ProcessImage> image;  // 0x1C12/0x1C13 compiled to bit copies
  RackConfig config;
  coe::ObjectDictionary od;
  std::unique_ptr<coe::SdoServer> sdo;
  std::unique_ptr<ParameterSet> params;
  std::shared_ptr<StateDirectory> dir;
  base::BackgroundWorker* worker = nullptr;  // the file work's (DeviceOptions::worker)
  std::unique_ptr<ParameterStore> store;
  std::unique_ptr<ParameterWriter> writer;  // after `store`: destroyed (and flushed) first
  std::unique_ptr<FirmwareStore> firmware;
  std::unique_ptr<FileAccess> files;
  std::unique_ptr<foe::FoeServer> foe;    // after `files` and `firmware`: destroyed first
  std::vector<uint8_t> running_firmware;  // the container the device "runs" since power-on
  FirmwareInfo built_in_firmware;         // the rack file's versions: what runs without a container
  std::string firmware_report;
  std::vector<uint8_t> default_payload;  // the parameter set as shipped (factory defaults)
  std::string state_dir;
  std::string load_report;
  EsmState state = EsmState::Init;
  SyncStatistics stats[2];
  int64_t clock_offset = 0;    // clock written to 0x2000:08 minus the system clock
  bool reset_factory = false;  // the 0xFBF0 command the worker executes is a factory reset
  std::chrono::steady_clock::time_point last_sync_at{};
  coe::diag::History history{kDiagnosisMessages};
  std::vector<uint8_t> repeat_images;     // repeats' recorded images that do not fit in place
  std::vector<uint8_t> enumerated;        // per module: enumerated now (module_enumeration.hpp)
  std::vector<CycleListener*> listeners;  // every listener, in the order they were added
  template <class F>
  void notify(F&& f) {
    for (CycleListener* l : listeners) f(*l);
  }
  template <class F>
  void notify_cycle(F&& f) {
    for (CycleListener* l : cycle_listeners) f(*l);
  }

  // The firmware round's time (base/round_time.hpp): one clock read per round, not per slave.
  uint32_t uptime_us(base::RoundTime::Clock::time_point at = base::RoundTime::now()) const {
    return static_cast<uint32_t>(
        std::chrono::duration_cast<std::chrono::microseconds>(at - power_on).count());
  }

  // Entries 1..sub0 of a latch array. Both arrays are read-only with one entry per module
  // (objects_cdp.cpp), so sub0 is fixed once the dictionary is built.
  static std::vector<coe::EntrySlot> array_slots(Object* o) {
    std::vector<coe::EntrySlot> slots;
    if (o == nullptr) return slots;
    for (uint8_t s = 1; s != 0 && s <= o->sub0(); ++s) slots.emplace_back(*o, s);
    return slots;
  }
  static void set_array(std::vector<coe::EntrySlot>& slots, uint64_t value) {
    for (coe::EntrySlot& slot : slots) slot.set(value);
  }
  // The process data starts: a cycle may repeat unless a mapped object runs a process-data
  // hook or a mapped entry is an input latch time (0xF6F0/0xF6F2 change without the outputs).
  void arm_repeats() {
    bool possible = !image->hooked();
    for (const uint16_t index : {uint16_t{0xF6F0}, uint16_t{0xF6F2}}) {
      if (const Object* o = od.find(index); o != nullptr && image->maps_input(*o)) possible = false;
    }
    repeats.arm(image->output_bytes(), image->input_bytes(), possible, repeat_images);
  }

  // --- stored parameters -------------------------------------------------------------------
  // A stored payload the device may apply: the right size and every value one an SDO write
  // would accept. Empty when it is; else the one-line reason it is ignored.
  std::string refuse(std::span<const uint8_t> payload) const {
    const std::string why = params->check(payload);
    return why.empty() ? why : "ignored parameter file " + store->path() + ": " + why;
  }

  // Start-up: applies the stored file if it is valid; reports what happened. A damaged,
  // foreign, oversized or planted file leaves the defaults (one line in load_report).
  void load_stored() {
    std::vector<uint8_t> payload;
    const auto r = store->load(params->fingerprint(), payload, load_report);
    if (r != ParameterStore::LoadResult::Loaded) return;
    if (std::string why = refuse(payload); !why.empty()) {
      load_report = std::move(why);
      return;
    }
    params->apply(payload);
  }

  // Every object back to its power-on value, then `stored` (already read by the worker) if it
  // passes the checks.
  void power_on_reset(const ParameterWriter::Result& stored) {
    od.for_each([](Object& o) { o.load_defaults(); });
    latch_esc_stale = true;
    history.bind(*od.find(coe::diag::kIndex));
    clock_offset = 0;
    load_report = stored.report;
    if (stored.stored) {
      if (std::string why = refuse(stored.bytes); !why.empty()) {
        load_report = std::move(why);
      } else {
        params->apply(stored.bytes);
      }
    }
    image->compile();
  }

  // Finishes the commands whose file work the worker has done (ESC thread; called before a
  // command object is read and whenever the mailbox is idle): every finished result, in the
  // order the worker finished them (a restore saved before a reset read the file back is
  // applied before the reset).
  void complete_jobs() {
    if (!writer->has_results()) return;
    using Job = ParameterWriter::Job;
    std::array<std::pair<Job, std::optional<ParameterWriter::Result>>, ParameterWriter::kJobs> done;
    for (size_t i = 0; i < done.size(); ++i) {
      const auto job = static_cast<Job>(i);
      done[i] = {job, writer->take(job)};
    }
    std::sort(done.begin(), done.end(), [](const auto& a, const auto& b) {
      const uint64_t sa = a.second ? a.second->sequence : UINT64_MAX;
      const uint64_t sb = b.second ? b.second->sequence : UINT64_MAX;
      return sa < sb;
    });
    for (auto& [job, r] : done) {
      if (r) complete(job, std::move(*r));
    }
  }

  void complete(ParameterWriter::Job job, ParameterWriter::Result r) {
    using Job = ParameterWriter::Job;
    switch (job) {
      case Job::Store:
        if (!r.ok) load_report = r.report;
        complete_command(od, 0xFBF2, r.ok ? cmd::kStatusDoneNoResponse : cmd::kStatusError);
        break;
      case Job::Checksum:
        complete_command(od, 0xFBF3, r.ok ? cmd::kStatusDoneWithResponse : cmd::kStatusError,
                         r.bytes);
        break;
      case Job::Load: {
        std::string why = r.ok ? refuse(r.stored ? r.bytes : default_payload) : r.report;
        load_report = why.empty() ? r.report : why;
        if (!why.empty()) {
          complete_command(od, 0xFBF4, cmd::kStatusError);
        } else {
          params->apply(r.stored ? r.bytes : default_payload);
          image->compile();
          complete_command(od, 0xFBF4, cmd::kStatusDoneNoResponse);
          notify([&](CycleListener& l) { l.on_parameters_loaded(*self); });
        }
        break;
      }
      case Job::Reset:
        if (!r.ok) {
          load_report = r.report;
          complete_command(od, 0xFBF0, cmd::kStatusError);
        } else {
          // The reset restarts the firmware: a container installed since power-on runs now
          // (read and verified by the worker with the reset job).
          apply_firmware(std::move(reset_firmware));
          apply_firmware_version(od, config.control);
          power_on_reset(r);  // every object, 0xFBF0 included, back to power-on values
          notify([&](CycleListener& l) { l.on_parameters_loaded(*self); });
          notify([&](CycleListener& l) { l.on_device_reset(*self, reset_factory); });
        }
        break;
      case Job::ReadFile:
        if (parameter_read_awaited) parameter_read = std::move(r);  // else: abandoned
        break;
      case Job::Restore:
        finish_restore(r);
        break;
    }
  }

  // --- DeviceRuntime: what the objects' behaviour (mdp/objects_*.cpp) asks of the device.
  int64_t clock_offset_s() const override { return clock_offset; }
  void set_clock_offset_s(int64_t offset) override { clock_offset = offset; }
  void recompile_process_image() override { image->compile(); }
  SyncStatistics& sync_statistics(bool outputs) override { return stats[outputs ? 0 : 1]; }
  std::chrono::steady_clock::time_point power_on_time() const override { return power_on; }
  void detect_modules() override {
    self->enumerate_modules(std::vector<uint8_t>(config.modules.size(), 1));
    notify([&](CycleListener& l) { l.on_detect_modules(*self); });
  }
  void start_device_reset(bool factory) override {
    reset_factory = factory;
    writer->submit_reset(params->fingerprint(), reset_factory,
                         [this, store = firmware.get(), vendor = config.control.vendor_id,
                          product = config.control.product_code] {
                           reset_firmware = read_firmware(*store, vendor, product);
                         });
  }
  void reset_exceptions() override {
    clear_latched_exceptions(config, od);
    notify([&](CycleListener& l) { l.on_exception_reset(*self); });
  }
  void start_store() override { writer->submit_store(params->fingerprint(), params->capture()); }
  void start_checksum(uint8_t algorithm) override {
    writer->submit_checksum(params->fingerprint(), algorithm, default_payload);
  }
  void start_load() override { writer->submit_load(params->fingerprint()); }
  void complete_commands() override { complete_jobs(); }

  // One diagnosis message and, when stored with 0x10F3:05 bit 0, its Emergency.
  coe::diag::AddResult emit(uint16_t text_id, uint16_t code, uint8_t reg,
                            const std::array<uint8_t, 5>& data, uint8_t rim, uint16_t module,
                            uint8_t channel, uint16_t detail, bool& queued) {
    coe::diag::Message m;
    m.diag_code = coe::diag::emergency_diag_code(code);
    m.type = diag::type_of(text_id);
    m.text_id = text_id;
    m.time_ns = self->diagnosis_time(m.local_time);
    m.add_u8(rim);
    m.add_u16(module);
    m.add_u8(channel);
    m.add_u16(detail);
    const auto r = history.add(m);
    queued = true;
    if (r == coe::diag::AddResult::Stored && history.emergency_enabled()) {
      const size_t before = sdo->emergency_overruns();
      sdo->queue_emergency(code, reg, data);
      raise_mailbox_hint();
      queued = sdo->emergency_overruns() == before;
    }
    return r;
  }

  // --- firmware and FoE (file_access.hpp) --------------------------------------------------
  // At power-on: the installed firmware container, if valid, sets the version objects and the
  // SII revision; else the built-in version runs (as a container with an empty payload).
  void load_firmware() {
    firmware = std::make_unique<FirmwareStore>(dir, *worker);
    const auto& cm = config.control;
    built_in_firmware = {cm.vendor_id, cm.product_code, cm.revision, cm.software_version,
                         cm.firmware_version.substr(0, kFirmwareShortVersionMax)};
    select_firmware();
  }
  // The installed container, read and verified: file work, so a device reset (0xFBF0) does it
  // on the worker thread (read_firmware_for_reset); only power-on calls it on the caller's.
  struct FirmwareChoice {
    std::optional<std::vector<uint8_t>> bytes;  // a valid container, else the built-in firmware
    FirmwareInfo info;
    std::string report;  // why an installed file was ignored (no file content)
  };
  // Written by the worker during a 0xFBF0 job; read once its result has been taken (the
  // writer's mutex orders the two).
  FirmwareChoice reset_firmware;
  static FirmwareChoice read_firmware(const FirmwareStore& store, uint32_t vendor_id,
                                      uint32_t product_code) {
    FirmwareChoice c;
    std::string detail;
    auto bytes = store.read_installed(kMaxFirmwareFile, detail);
    if (!bytes) return c;
    if (verify_firmware(*bytes, vendor_id, product_code, c.info, detail) == foe::FoeError::None) {
      c.bytes = std::move(bytes);
    } else {
      c.report = "ignored firmware " + store.path() + ": " + detail + "; ";
    }
    return c;
  }
  // Power-on and device reset (0xFBF0): the versions of the container that runs from now on.
  void select_firmware() {
    apply_firmware(read_firmware(*firmware, config.control.vendor_id, config.control.product_code));
  }
  void apply_firmware(FirmwareChoice choice) {
    auto& cm = config.control;
    firmware_report = std::move(choice.report);
    if (choice.bytes) {
      const FirmwareInfo& info = choice.info;
      cm.revision = info.revision;
      cm.software_version = info.software_version;
      cm.firmware_version =
          info.short_version.empty() ? built_in_firmware.short_version : info.short_version;
      running_firmware = std::move(*choice.bytes);
      firmware_report = "firmware " + cm.software_version + " from " + firmware->path();
      return;
    }
    cm.revision = built_in_firmware.revision;
    cm.software_version = built_in_firmware.software_version;
    cm.firmware_version = built_in_firmware.short_version;
    std::string error;
    running_firmware = pack_firmware(built_in_firmware, {}, error).value_or(std::vector<uint8_t>{});
    firmware_report += "firmware " + cm.software_version + " (built in)";
  }

  // --- parameters.bin over FoE (file_access.hpp, docs/FOE.md) ------------------------------
  // The file work is a job of the parameter writer, so it runs on the worker after any store
  // (0xFBF2), load or reset queued before it, in that order, and never on this thread. The
  // jobs own their data (no pointer to this device); the objects change only here, when the
  // result is taken (complete_jobs).
  bool parameter_read_awaited = false;
  std::optional<ParameterWriter::Result> parameter_read;  // the worker's read, once it is done
  bool restore_pending = false;                           // a restore's save is queued/running
  std::vector<uint8_t> restore_payload;                   // ... and the set it applies when saved
  foe::CommitProgress restore_outcome;
  std::string restore_detail;

  void start_parameter_read() {
    parameter_read.reset();
    parameter_read_awaited = true;
    writer->submit_read_file(params->fingerprint());
  }

  foe::ReadProgress poll_parameter_read(std::vector<uint8_t>& contents) {
    complete_jobs();
    if (!parameter_read_awaited) return {false, foe::FoeError::NotDefined};
    if (!parameter_read) return {true, foe::FoeError::None};
    // The parameters as stored (what 0xFBF3 hashes): the stored file if it is valid, else the
    // shipped defaults.
    const ParameterWriter::Result& r = *parameter_read;
    const bool valid = r.stored && refuse(r.bytes).empty();
    contents = ParameterStore::encode(params->fingerprint(), valid ? r.bytes : default_payload);
    abort_parameter_read();
    return {false, foe::FoeError::None};
  }

  void abort_parameter_read() {
    parameter_read_awaited = false;
    parameter_read.reset();
  }

  foe::FoeError restore_parameters(std::span<const uint8_t> file, std::string& detail) {
    if (restore_pending) {
      detail = "a parameter restore is still running";
      return foe::FoeError::AccessDenied;
    }
    std::vector<uint8_t> payload;
    switch (ParameterStore::decode(file, params->fingerprint(), payload, detail, "over FoE")) {
      case ParameterStore::LoadResult::Loaded:
        break;
      case ParameterStore::LoadResult::Foreign:
        return foe::FoeError::FileIncompatible;
      default:
        return foe::FoeError::WrongChecksum;
    }
    // Checked as an SDO write of the same values would be (as stored files are at load).
    if (const std::string why = params->check(payload); !why.empty()) {
      detail = "parameter file over FoE: " + why;
      return foe::FoeError::Illegal;
    }
    restore_payload = payload;
    restore_pending = true;
    writer->submit_restore(params->fingerprint(), std::move(payload));
    detail.clear();
    return foe::FoeError::None;
  }

  // The worker saved the restored set (or failed to): apply it, or keep the old one.
  void finish_restore(const ParameterWriter::Result& r) {
    restore_pending = false;
    if (r.ok) {
      params->apply(restore_payload);
      image->compile();
      notify([&](CycleListener& l) { l.on_parameters_loaded(*self); });
      restore_outcome = {false, foe::FoeError::None, 1, 1};
      restore_detail = "restored parameters";
    } else {
      // ETG.1000.6 §5.8 FoE error codes: 0x8003 Disk full for a full disk (or quota, or file
      // size limit), 0x8011 Flash problem for any other failure to write the state directory.
      const int e = r.error_number;
      const bool full = e == ENOSPC || e == EDQUOT || e == EFBIG;
      restore_outcome = {false, full ? foe::FoeError::DiskFull : foe::FoeError::FlashProblem, 1, 1};
      restore_detail = "parameters not restored, the old ones stay: " + r.report;
    }
    restore_payload = {};
  }

  foe::CommitProgress poll_restore(std::string& detail) {
    complete_jobs();
    // Done / Entire: one step (the save), 0 of 1 while it runs.
    if (restore_pending) return {true, foe::FoeError::None, 0, 1};
    detail = restore_detail;
    return restore_outcome;
  }

  void start_foe(uint32_t password) {
    FileAccessHooks hooks;
    hooks.state = [this] { return state; };
    hooks.start_parameter_read = [this] { start_parameter_read(); };
    hooks.poll_parameter_read = [this](std::vector<uint8_t>& contents) {
      return poll_parameter_read(contents);
    };
    hooks.abort_parameter_read = [this] { abort_parameter_read(); };
    hooks.restore_parameters = [this](std::span<const uint8_t> f, std::string& detail) {
      return restore_parameters(f, detail);
    };
    hooks.poll_restore = [this](std::string& detail) { return poll_restore(detail); };
    hooks.running_firmware = [this] { return running_firmware; };
    const uint32_t vendor = config.control.vendor_id, product = config.control.product_code;
    hooks.verify_firmware = [vendor, product](std::span<const uint8_t> f, std::string& detail) {
      FirmwareInfo info;
      return verify_firmware(f, vendor, product, info, detail);
    };
    hooks.log = [](const std::string& line) {
      std::fprintf(stderr, "rackcat: %s\n", line.c_str());
    };
    files = std::make_unique<FileAccess>(*firmware, password, std::move(hooks));
    foe::FoeLimits limits;
    limits.max_file_size = kMaxFirmwareFile;
    foe = std::make_unique<foe::FoeServer>(*files, limits);
  }
};

Device::Device(RackConfig config, DeviceOptions options) : impl_(std::make_unique<Impl>()) {
  Impl& d = *impl_;
  d.self = this;
  d.config = std::move(config);
  d.listeners.reserve(16);
  d.cycle_listeners.reserve(16);
  d.dir = options.state ? std::move(options.state)
                        : StateDirectory::open(options.state_dir.empty() ? default_state_dir()
                                                                         : options.state_dir);
  d.state_dir = d.dir->path();
  d.worker = options.worker != nullptr ? options.worker : &base::BackgroundWorker::shared();
  d.load_firmware();  // before the dictionary: the firmware's version is what it reports
  build_object_dictionary(d.config, d.od);
  d.latch_local_slots = Impl::array_slots(d.od.find(0xF6F0));
  d.latch_esc_slots = Impl::array_slots(d.od.find(0xF6F2));
  d.params = std::make_unique<ParameterSet>(d.od, d.config);
  d.default_payload = d.params->capture();
  d.store = std::make_unique<ParameterStore>(d.dir);
  d.writer = std::make_unique<ParameterWriter>(*d.store, *d.worker);
  d.writer->notify_results(&d.mailbox_hint);
  d.image.emplace(d.od);
  attach_device_behaviour(d.config, d.od, d);
  d.history.bind(*d.od.find(coe::diag::kIndex));
  if (options.load_stored_parameters) {
    d.load_stored();
  } else {
    d.load_report = "stored parameters not loaded";
  }
  d.image->compile();
  d.enumerated.assign(d.config.modules.size(), 1);
  d.sdo = std::make_unique<coe::SdoServer>(d.od);
  d.start_foe(d.config.control.foe_password);
}

Device::~Device() = default;

const RackConfig& Device::config() const {
  return impl_->config;
}
coe::ObjectDictionary& Device::dictionary() {
  impl_->disturb();  // the caller may change what the next cycle reads
  return impl_->od;
}
const coe::ObjectDictionary& Device::dictionary() const {
  impl_->flush_latch();  // the objects as they are
  return impl_->od;
}
std::span<const Module> Device::modules() const {
  return impl_->config.modules;
}

mailbox::Answer Device::coe_request(std::span<const uint8_t> request, std::span<uint8_t> reply) {
  impl_->disturb();
  const mailbox::Answer a = impl_->sdo->handle(request, reply, impl_->state);
  impl_->raise_mailbox_hint();  // e.g. an SDO Information list in fragments
  return a;
}

bool Device::mailbox_pending() const {
  Impl& d = *impl_;
  // Nothing can have become pending since the last full check found nothing (one load of a
  // line the cyclic path touches anyway, instead of three objects elsewhere in memory).
  if (!d.mailbox_hint.load(std::memory_order_seq_cst)) return false;
  // Lower the hint, then look: whatever is published after the look raises it again.
  d.mailbox_hint.store(false, std::memory_order_seq_cst);
  std::atomic_thread_fence(std::memory_order_seq_cst);
  if (d.writer->has_results() || !d.foe->idle() || d.sdo->has_pending()) {
    d.mailbox_hint.store(true, std::memory_order_seq_cst);
    return true;
  }
  return false;
}

size_t Device::coe_poll(std::span<uint8_t> reply) {
  impl_->disturb();  // a command's result may change objects
  impl_->complete_jobs();
  return impl_->sdo->poll(reply);
}

mailbox::Answer Device::foe_request(std::span<const uint8_t> request, size_t capacity,
                                    std::span<uint8_t> reply) {
  impl_->disturb();
  const mailbox::Answer a = impl_->foe->handle_mailbox(request, capacity, reply);
  impl_->raise_mailbox_hint();  // an open transfer (its timeout, a deferred read)
  return a;
}

size_t Device::foe_poll(std::span<uint8_t> reply) {
  impl_->disturb();
  impl_->complete_jobs();
  return impl_->foe->poll(reply);
}

bool Device::raise_emergency(uint16_t error_code, uint8_t error_register,
                             std::array<uint8_t, 5> data) {
  const uint16_t text = diag::text_for_emergency(error_code, data);
  const uint16_t mask = le::get16(&data[3]);
  const auto channel = static_cast<uint8_t>(mask ? std::countr_zero(mask) : 0xFF);
  const uint16_t detail = text == diag::text::kEmergency ? error_code : 0;
  bool queued = true;
  impl_->emit(text, error_code, error_register, data, data[0], data[1], channel, detail, queued);
  return queued;
}

coe::diag::AddResult Device::report_diagnosis(const DiagnosisReport& r) {
  const diag::DiagText* t = diag::find(r.text_id);
  const uint16_t code = t ? t->emergency_code : 0;
  const uint8_t reg = t ? t->error_register : 0;
  const uint16_t mask = r.channel < 16 ? static_cast<uint16_t>(1u << r.channel) : 0;
  const std::array<uint8_t, 5> data = {r.rim, static_cast<uint8_t>(r.module), 0xFF,
                                       static_cast<uint8_t>(mask), static_cast<uint8_t>(mask >> 8)};
  bool queued = true;
  return impl_->emit(r.text_id, code, reg, data, r.rim, r.module, r.channel, r.detail, queued);
}

const coe::diag::History& Device::diagnosis() const {
  return impl_->history;
}

void Device::reset_exceptions() {
  impl_->disturb();
  impl_->reset_exceptions();
}

uint64_t Device::diagnosis_time(bool& local) const {
  const Impl& d = *impl_;
  const auto now = std::chrono::steady_clock::now();
  const auto since_sync = now - d.last_sync_at;
  if (d.last_sync_ns != 0 && since_sync < std::chrono::seconds(1)) {
    local = false;
    return d.last_sync_ns +
           static_cast<uint64_t>(
               std::chrono::duration_cast<std::chrono::nanoseconds>(since_sync).count());
  }
  local = true;
  return static_cast<uint64_t>(
      std::chrono::duration_cast<std::chrono::nanoseconds>(now - d.power_on).count());
}

void Device::enumerate_modules(std::span<const uint8_t> present) {
  Impl& d = *impl_;
  d.disturb();
  std::vector<uint8_t> now(d.config.modules.size(), 1);
  for (size_t i = 0; i < now.size() && i < present.size(); ++i) now[i] = present[i] != 0;
  mdp::enumerate_modules(d.od, d.config, d.enumerated, now);
  d.enumerated = std::move(now);
  d.image->compile();
}

uint16_t Device::request_state(EsmState from, EsmState to) {
  impl_->disturb();
  const bool entering_safeop = to == EsmState::SafeOp || to == EsmState::Op;
  if (entering_safeop && (from == EsmState::PreOp || from == EsmState::Init)) {
    if (module_lists_mismatch(impl_->od)) {
      // ETG.5001.1: the configured list must equal the detected one; the log says where not.
      std::fprintf(stderr, "rackcat: PREOP->SAFEOP refused (AL 0x%04X): %s\n",
                   kAlModuleIdentMismatch, module_list_difference(impl_->od).c_str());
      return kAlModuleIdentMismatch;
    }
    // The PDO configuration the master left in PREOP must compile (ETG.1000.6 Table 11:
    // 0x001D invalid output configuration, 0x001E invalid input configuration).
    coe::PdoDirection failed = coe::PdoDirection::Rx;
    if (impl_->image->compile(&failed) != AbortCode::None) {
      return failed == coe::PdoDirection::Rx ? kAlInvalidOutputConfig : kAlInvalidInputConfig;
    }
  }
  return 0;
}

void Device::state_changed(EsmState from, EsmState to) {
  Impl& d = *impl_;
  d.state = to;
  d.raise_mailbox_hint();
  if (to == EsmState::Init) {
    d.sdo->reset();
    d.foe->reset();
  }
  if (to == EsmState::SafeOp && from == EsmState::PreOp) {
    d.image->compile();
    d.arm_repeats();
  }
  d.disturb();
  d.notify([&](CycleListener& l) { l.on_state_changed(*this, from, to); });
}

EsmState Device::state() const {
  return impl_->state;
}

uint16_t Device::output_bytes() const {
  return static_cast<uint16_t>(impl_->image->output_bytes());
}
uint16_t Device::input_bytes() const {
  return static_cast<uint16_t>(impl_->image->input_bytes());
}

void Device::write_outputs(std::span<const uint8_t> sm2) {
  Impl& d = *impl_;
  if (d.repeats.skip_outputs(sm2, [&d] { return d.listeners_repeat(); })) return;
  d.image->write_outputs(sm2);
  d.notify_cycle([&](CycleListener& l) { l.on_outputs(*this); });
}

bool Device::read_inputs(std::span<uint8_t> sm3) {
  Impl& d = *impl_;
  if (!d.repeats.inputs_wanted([&d] { return d.listeners_repeat(); })) {
    // A repeated cycle or refresh: SM3 holds these inputs already; only the latch time moves
    // (0xF6F0 is not mapped, or the device would not repeat).
    d.latch_pending = true;
    d.latch_at = base::RoundTime::now();
    return false;
  }
  d.latch_pending = false;
  d.notify_cycle([&](CycleListener& l) { l.before_inputs(*this); });
  // 0xF6F0/0xF6F2: the input latch time of every module is this update.
  if (!d.latch_local_slots.empty()) Impl::set_array(d.latch_local_slots, d.uptime_us());
  if (d.latch_esc_stale || d.latch_esc_value != d.last_sync_ns) {
    Impl::set_array(d.latch_esc_slots, d.last_sync_ns);
    d.latch_esc_value = d.last_sync_ns;
    d.latch_esc_stale = false;
  }
  d.image->read_inputs(sm3);
  d.repeats.inputs_made(sm3, [&d] { return d.listeners_repeat(); });
  return true;
}

void Device::disturb() {
  impl_->disturb();
}

void Device::sync_event(int which, uint64_t system_time_ns) {
  Impl& d = *impl_;
  d.disturb();
  if (which == 0) {
    d.last_sync_ns = system_time_ns;
    d.last_sync_at = std::chrono::steady_clock::now();
  }
  d.notify_cycle([&](CycleListener& l) { l.on_sync(*this, which, system_time_ns); });
}

void Device::watchdog_expired() {
  impl_->disturb();
  impl_->notify([&](CycleListener& l) { l.on_watchdog_expired(*this); });
}

SyncStatistics& Device::sync_statistics(bool outputs) {
  impl_->disturb();
  return impl_->sync_statistics(outputs);
}

void Device::add_listener(CycleListener* listener, ListenerScope scope) {
  impl_->disturb();
  auto& v = impl_->listeners;
  if (std::find(v.begin(), v.end(), listener) != v.end()) return;
  v.push_back(listener);
  if (scope == ListenerScope::All) impl_->cycle_listeners.push_back(listener);
}

void Device::remove_listener(CycleListener* listener) {
  impl_->disturb();
  for (auto* v : {&impl_->listeners, &impl_->cycle_listeners}) {
    v->erase(std::remove(v->begin(), v->end(), listener), v->end());
  }
}

const std::string& Device::state_dir() const {
  return impl_->state_dir;
}
std::string Device::parameter_file() const {
  return impl_->store->path();
}
const std::string& Device::load_report() const {
  return impl_->load_report;
}
const std::string& Device::firmware_report() const {
  return impl_->firmware_report;
}

}  // namespace rackcat::mdp
