// The user's fuzzing dictionary (--dict), in AFL's format: one entry per line,
// `name="value"` or `"value"`, with \xHH, \\ and \" escapes; '#' starts a comment. Two-byte
// entries are 16-bit words (big-endian, as Modbus sends them) used as addresses and values;
// longer ones are spliced into requests. A bare number (decimal or 0x hex, up to 0xFFFF) is a
// word too, for lists of register addresses.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "util/error.hpp"

namespace mbstorm::netfuzz {

struct Dictionary {
    std::vector<std::uint16_t> words;
    std::vector<std::vector<std::uint8_t>> tokens;
};

// An InvalidInput error placed at "FILE:LINE" on the first bad line.
Result<Dictionary> parse_dictionary(const std::string& text, const std::string& name);
// --dict FILE: NotFound when there is no such file.
Result<Dictionary> load_dictionary(const std::string& path);

}  // namespace mbstorm::netfuzz
