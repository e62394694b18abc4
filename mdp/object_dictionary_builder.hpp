// Builds the Fusion.IO object dictionary (guide Appendix A, ETG.5001 MDP, ETG.5003 CDP,
// ETG.1000.6 communication area) for a rack configuration. The same function feeds the running
// device (mdp::Device), the `od` command and the ESI/SII generators (esi/), so all of them
// describe one dictionary.
//
// Validation hooks installed here capture `od` by reference: build into the dictionary that
// will be used and do not move it afterwards. Behaviour that needs the running device (command
// objects, clock, counters) is declared next to the objects, in the same file
// (attach_*_behaviour), and attached by mdp::Device through the DeviceRuntime interface.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "coe/object_dictionary.hpp"
#include "mdp/device_runtime.hpp"
#include "mdp/rack_config.hpp"

namespace rackcat::mdp {

void build_object_dictionary(const RackConfig& config, coe::ObjectDictionary& od);

// The parts, one per area (mdp/objects_*.cpp), in index order.
void add_communication_objects(const RackConfig& config,
                               coe::ObjectDictionary& od);                          // 0x1000-0x1C33
void add_device_info_objects(const RackConfig& config, coe::ObjectDictionary& od);  // 0x2000-0x3nn1
void add_safe_state_objects(const RackConfig& config, coe::ObjectDictionary& od);   // 0x4nnX
void add_substitute_objects(const RackConfig& config, coe::ObjectDictionary& od);   // 0x4nn8..C
void add_tc_uart_objects(const RackConfig& config, coe::ObjectDictionary& od);  // 0x5nnX, 0x0800+
void add_process_data_objects(const RackConfig& config,
                              coe::ObjectDictionary& od);  // 0x6nnX/0x7nnX
void add_encoder_objects(const RackConfig& config,
                         coe::ObjectDictionary& od);  // 0x8nn0/0x8nn1/0x9nn0 (encoder cards)
void add_mdp_objects(const RackConfig& config, coe::ObjectDictionary& od);        // 0xF000-0xF050
void add_exception_objects(const RackConfig& config, coe::ObjectDictionary& od);  // 0xF380-0xF3A8
void add_cdp_objects(const RackConfig& config, coe::ObjectDictionary& od);        // 0xF6F0-0xF9F8
void add_command_objects(const RackConfig& config, coe::ObjectDictionary& od);    // 0xFBF0-0xFBF4
void add_diagnosis_objects(const RackConfig& config, coe::ObjectDictionary& od);  // 0x10F3, 0x1BFF

// What the objects do in a running device (mdp/device_runtime.hpp), each in the file of its
// objects: attach_device_behaviour runs them all.
void attach_device_behaviour(const RackConfig& config, coe::ObjectDictionary& od,
                             DeviceRuntime& device);
void attach_communication_behaviour(coe::ObjectDictionary& od,
                                    DeviceRuntime& device);  // 0x1C12/13/32/33, user PDOs
void attach_device_info_behaviour(coe::ObjectDictionary& od, DeviceRuntime& device);  // 0x2000
void attach_mdp_behaviour(coe::ObjectDictionary& od, DeviceRuntime& device);          // 0xF002
void attach_cdp_behaviour(coe::ObjectDictionary& od, DeviceRuntime& device);          // 0xF9F6
void attach_command_behaviour(coe::ObjectDictionary& od, DeviceRuntime& device);      // 0xFBF0-4

// A command object's job has finished: status (subindex 2) and response (subindex 3: status,
// 0, response bytes).
void complete_command(coe::ObjectDictionary& od, uint16_t index, uint8_t status,
                      std::span<const uint8_t> response = {});
// Subindex 1 of a command object back to its read value (the capability bytes, or zeros), so
// the image never holds a command sequence and a complete-access write-back executes nothing.
void restore_command(coe::Object& obj);
// 0xFBF1: the latched exception objects 0xF390..0xF398 and the latched bits 31..2 of
// 0x2rr1:08 cleared (guide §3.3).
void clear_latched_exceptions(const RackConfig& config, coe::ObjectDictionary& od);

// 0x10F3 diagnosis history size (ETG.1020 ch. 13 allows 1..250) and the device-level TxPDO
// that maps 0x10F3:04 "New Messages Available".
inline constexpr uint8_t kDiagnosisMessages = 64;
inline constexpr uint16_t kDiagnosisTxPdo = 0x1BFF;

// 0x1C32/0x1C33:01 synchronisation types (ETG.1020 §8.2.2, ETG.1000.6 Table 67).
inline constexpr uint16_t kSyncFreeRun = 0x00;
inline constexpr uint16_t kSyncSmEvent = 0x01;  // SM2 event (0x1C32) / SM3 event (0x1C33)
inline constexpr uint16_t kSyncDcSync0 = 0x02;
inline constexpr uint16_t kSyncWithSm2 = 0x22;  // 0x1C33 only: inputs latched on the SM2 event
inline constexpr uint16_t kSyncTypesSupported =
    0x0007;  // free run | SM | DC SYNC0 (bits 4..2 = 001)

// 0x1C12/0x1C13 use coe's PDO assignment validator (coe/pdo_mapping.hpp: subindex 0 must be 0
// while entries change (0x06010003), an index outside the direction's mapping range 0x06040043,
// a missing mapping object 0x06020000, more than the SM maximum 0x06040042) plus one rule of
// their own: the same PDO assigned twice is 0x06040043.

// The module ident lists: 0xF050 (detected) and 0xF030 (configured) as they stand; true when
// 0xF030 is in use (subindex 0 != 0) and differs from 0xF050 (ETG.5001.1: AL status 0x0070).
bool module_lists_mismatch(const coe::ObjectDictionary& od);

// The default 0x1C12 (rx) / 0x1C13 assignment: the PDO of each enumerated module
// (`enumerated[i]` != 0 for module i + 1; an empty span enumerates every module) that has one,
// in module order, cut where the SM maximum would be exceeded.
std::vector<uint16_t> default_assignment(const RackConfig& config, bool rx,
                                         std::span<const uint8_t> enumerated);

}  // namespace rackcat::mdp
