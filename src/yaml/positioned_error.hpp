// The error every YAML document mbstorm reads raises, at a place in it; each kind of document
// (device descriptions, scenarios) derives its own type so callers can tell them apart.
#pragma once

#include <stdexcept>
#include <string>

namespace mbstorm::yaml {

class PositionedError : public std::runtime_error {
  public:
    PositionedError(const std::string& message, int line, int column)
        : std::runtime_error(message), line_(line), column_(column) {}
    int line() const noexcept { return line_; }      // 1-based, 0 when unknown
    int column() const noexcept { return column_; }  // 1-based, 0 when unknown

  private:
    int line_;
    int column_;
};

}  // namespace mbstorm::yaml
