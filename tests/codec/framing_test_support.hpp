// Small helpers shared by the framing tests.
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <string_view>
#include <vector>

#include "codec/values.hpp"

namespace mbstorm::codec::framing_test {

using ByteVec = std::vector<std::uint8_t>;

// "11 03 00 6B" -> bytes; fails the test on malformed text.
inline ByteVec hex_bytes(std::string_view text) {
    ByteVec out(text.size() / 2 + 1);
    const HexParseResult r = parse_hex(text, out);
    EXPECT_TRUE(r.ok()) << "bad hex in test vector: " << text;
    out.resize(r.size);
    return out;
}

inline ByteVec to_vec(Bytes b) {
    return ByteVec(b.begin(), b.end());
}

}  // namespace mbstorm::codec::framing_test
