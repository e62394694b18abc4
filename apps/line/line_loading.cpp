// Line loading shared by `run` and `check` (see line_loading.hpp).
#include "apps/line/line_loading.hpp"

#include <cstdio>

#include "apps/line/eni_file.hpp"
#include "apps/rack_slave/rack_loading.hpp"
#include "device/esi_error.hpp"
#include "mdp/rack_config.hpp"

namespace rackcat::apps {

std::optional<LineFile> load_line_or_report(const LineSource& source) {
  try {
    LineFile line = source.eni.empty() ? load_line_file(source.line)
                                       : load_eni_file(source.eni, source.esi_dir);
    for (const auto& d : line.devices) {
      if (d.rack) validate_rack(*d.rack);
    }
    return line;
  } catch (const device::FileError& e) {
    std::fprintf(stderr, "%s\n", e.what());
  } catch (const mdp::ConfigError& e) {
    std::fprintf(stderr, "%s\n", e.what());
  }
  return std::nullopt;
}

}  // namespace rackcat::apps
