#include "mdp/object_dictionary_builder.hpp"

namespace rackcat::mdp {

void build_object_dictionary(const RackConfig& config, coe::ObjectDictionary& od) {
  add_communication_objects(config, od);
  add_device_info_objects(config, od);
  add_safe_state_objects(config, od);
  add_substitute_objects(config, od);
  add_tc_uart_objects(config, od);
  add_process_data_objects(config, od);
  add_encoder_objects(config, od);
  add_mdp_objects(config, od);
  add_exception_objects(config, od);
  add_cdp_objects(config, od);
  add_command_objects(config, od);
  add_diagnosis_objects(config, od);
}

void attach_device_behaviour(const RackConfig&, coe::ObjectDictionary& od, DeviceRuntime& device) {
  attach_communication_behaviour(od, device);
  attach_device_info_behaviour(od, device);
  attach_mdp_behaviour(od, device);
  attach_cdp_behaviour(od, device);
  attach_command_behaviour(od, device);
}

}  // namespace rackcat::mdp
