// libFuzzer target of the control API request handler (modules::ControlApi::handle, the part
// behind the HTTP server: method, path and JSON body), on the default rack in OP, without a
// network. Input: "METHOD\nPATH\nBODY" (missing lines are empty). Every request must be
// answered with a status and a JSON body ({"error": ...} with 4xx for bad requests; a bad
// source description is refused with 500 + the source's ConfigError text); a crash, hang or
// sanitizer report is a bug. The rack persists across inputs and runs
// one process-data cycle after each request, so sequences of requests (a source change, then
// a cycle that evaluates it) are explored.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "mdp/device.hpp"
#include "mdp/rack_config.hpp"
#include "modules/control/control_api.hpp"
#include "modules/rack/rack.hpp"

namespace {

using rackcat::EsmState;

struct Harness {
  double clock = 0.0;
  uint64_t cycles = 0;
  rackcat::mdp::Device device;
  rackcat::modules::Rack rack;
  rackcat::modules::ControlApi api;
  std::vector<uint8_t> outputs, inputs;

  static rackcat::mdp::DeviceOptions device_options() {
    rackcat::mdp::DeviceOptions o;
    o.state_dir = (std::filesystem::temp_directory_path() / "rackcat-fuzz-control-api").string();
    o.load_stored_parameters = false;
    return o;
  }
  static rackcat::modules::RackOptions rack_options(double* clock) {
    rackcat::modules::RackOptions o;
    o.clock = [clock] { return *clock; };
    return o;
  }

  Harness()
      : device(rackcat::mdp::default_rack(), device_options()),
        rack(device, rack_options(&clock)),
        // No post function: requests run on the calling thread, as on the device thread.
        api(rack, nullptr),
        outputs(device.output_bytes(), 0),
        inputs(device.input_bytes(), 0) {
    device.state_changed(EsmState::Init, EsmState::PreOp);
    device.state_changed(EsmState::PreOp, EsmState::SafeOp);
    device.state_changed(EsmState::SafeOp, EsmState::Op);
  }

  void cycle() {
    clock += 0.001;
    ++cycles;
    for (size_t i = 0; i < outputs.size(); ++i)
      outputs[i] = static_cast<uint8_t>((cycles + i) & 0xFF);
    device.write_outputs(outputs);
    device.read_inputs(inputs);
  }
};

std::string_view next_line(std::string_view& rest) {
  const size_t nl = rest.find('\n');
  std::string_view line = rest.substr(0, nl);
  rest = nl == std::string_view::npos ? std::string_view() : rest.substr(nl + 1);
  return line;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static Harness* h = new Harness();  // lives for the whole run (state across inputs)
  std::string_view rest(reinterpret_cast<const char*>(data), size);
  const std::string_view method = next_line(rest);
  const std::string_view path = next_line(rest);
  const auto response = h->api.handle(method, path, rest);
  // Every refusal carries its reason.
  if (response.status < 200 || response.status > 599) std::abort();
  if (response.status >= 400 && !response.body.contains("error")) std::abort();
  (void)response.body.dump();
  h->cycle();
  return 0;
}
