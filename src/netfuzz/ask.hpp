// Asking the target a list of requests and collecting the answers: discovery and model
// learning use it. Over MBAP the frames go out at once on one connection, each with its index
// as transaction id; over RTU and ASCII (no transaction ids) one by one, each answer awaited.
#pragma once

#include <cstdint>
#include <vector>

#include "netfuzz/link.hpp"

namespace mbstorm::netfuzz {

// The answers' PDUs by frame (empty: no answer). `connected` false: no connection opened.
std::vector<std::vector<std::uint8_t>> ask_pipelined(
    Connector& target, const std::vector<std::vector<std::uint8_t>>& frames, int timeout_ms,
    bool& connected);

}  // namespace mbstorm::netfuzz
