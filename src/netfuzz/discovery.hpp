// Discovery, the campaign's first stage: which request the target answers (the probe every
// later stage uses to see it is up), the function codes it does not implement, those it is
// silent to, its vendor extensions, and whether it drops what is pipelined behind an exception.
// And the wait for a target that went down to answer that probe again.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "codec/function_code.hpp"
#include "netfuzz/link.hpp"
#include "netfuzz/oracle.hpp"
#include "netfuzz/restart_command.hpp"

namespace mbstorm::netfuzz {

// A valid request of `info`'s function code, made from its request shape in the codec's table
// (writes aimed at 0x5FFF, below the default state range).
std::vector<std::uint8_t> canonical_request(const codec::FunctionInfo& info);
// One canonical request of every public function code.
const std::vector<std::vector<std::uint8_t>>& canonical_requests();

// Learns the probe request, the function codes the target does not support and its vendor
// extensions. An Error when the target cannot be reached or answers no probe usably.
Error discover_target(Connector& target, std::uint8_t unit, int timeout_ms, TargetProfile& profile);

// Waits (connects retried with backoff) until the target answers the probe, starting
// `restart_cmd` first when given. False when it does not come back within `wait_ms` of the
// command returning (or, for a command that keeps running, of its start plus a minute), or by
// `deadline_ns` (0: none).
bool wait_for_target(Connector& target, const TargetProfile& profile,
                     const std::string& restart_cmd, int wait_ms, int timeout_ms,
                     std::int64_t deadline_ns = 0);
// The same with the caller's `command`, so that one still running from an earlier restart (the
// target in the foreground) is waited for, not started twice.
bool wait_for_target_with(RestartCommand& command, Connector& target, const TargetProfile& profile,
                          const std::string& restart_cmd, int wait_ms, int timeout_ms,
                          std::int64_t deadline_ns);

}  // namespace mbstorm::netfuzz
