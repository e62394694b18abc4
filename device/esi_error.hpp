// The one error an ESI, line or ENI file gets: "FILE:LINE: reason". A file with unsupported or
// contradictory content is refused as a whole; nothing of it is used.
#pragma once

#include <cstddef>
#include <stdexcept>
#include <string>

namespace rackcat::device {

class FileError : public std::runtime_error {
 public:
  FileError(const std::string& file, size_t line, const std::string& reason)
      : std::runtime_error(file + ":" + std::to_string(line) + ": " + reason),
        file_(file),
        line_(line),
        reason_(reason) {}
  const std::string& file() const { return file_; }
  size_t line() const { return line_; }
  const std::string& reason() const { return reason_; }

 private:
  std::string file_;
  size_t line_;
  std::string reason_;
};

}  // namespace rackcat::device
