// Quoting for the few tests that run a tool through popen(): the checkout (and so every path the
// build hands a test) may contain spaces or quotes, e.g. "/tmp/rack cat/main".
#pragma once

#include <string>
#include <string_view>

namespace rackcat::testing {

// `text` as one POSIX shell word: wrapped in single quotes, each ' written as '\''.
inline std::string shell_quote(std::string_view text) {
  std::string quoted = "'";
  for (char c : text) {
    if (c == '\'') {
      quoted += "'\\''";
    } else {
      quoted += c;
    }
  }
  quoted += '\'';
  return quoted;
}

}  // namespace rackcat::testing
