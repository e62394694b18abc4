// Loading a line for a subcommand: a line file (`--line FILE`) or an ENI with its ESI directory
// (`--eni FILE --esi-dir DIR`). `rackcat run` and `rackcat check` both go through
// load_line_or_report, so they accept and refuse the same files: the file is read
// (apps/line/line_file.hpp, apps/line/eni_file.hpp) and every rack of the line is validated with
// its drivers offline like a rack file given with --config (apps/rack_slave/rack_loading.hpp). A
// bad file is one line "FILE:LINE: problem" on stderr.
#pragma once

#include <optional>
#include <string>

#include "apps/line/line_file.hpp"

namespace rackcat::apps {

struct LineSource {
  std::string line;     // a line file, or
  std::string eni;      // an ENI file
  std::string esi_dir;  // with the directory of its ESI (and rack) files
};

// The validated line, or nullopt after printing the error.
std::optional<LineFile> load_line_or_report(const LineSource& source);

}  // namespace rackcat::apps
