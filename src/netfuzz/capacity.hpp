// The connection-capacity oracle: hold an increasing number of concurrent connections (up to a
// cap) and check at each step that a fresh connection is still served and that the oldest one
// still answers. A server may refuse or close connections beyond its limit; it must not accept
// them and then leave them (or its existing clients) unanswered.
#pragma once

#include <cstdint>

#include "net/socket.hpp"
#include "netfuzz/link.hpp"
#include "netfuzz/oracle.hpp"

namespace mbstorm::netfuzz {

struct CapacityResult {
    Verdict verdict;            // empty: the target held up
    std::uint32_t held = 0;     // most connections open at once that were all answered
    std::uint32_t refused = 0;  // connects refused or closed by the target (allowed)
    bool target_down = false;   // a fresh connection failed after the check
    std::uint32_t opened = 0;   // connections open (or tried) when the check ended
};

class DeathWatch;

// `deadline_ns` (0: none) bounds the whole check; it stops early, clean, when reached. With an
// armed `watch`, a target process that dies at a step is a crash even if a supervisor has it
// back at once.
CapacityResult check_capacity(Connector& target, const TargetProfile& profile,
                              std::uint32_t max_connections, int timeout_ms,
                              std::int64_t deadline_ns, DeathWatch* watch = nullptr);

// How many connections this process can hold open at once (RLIMIT_NOFILE, raised to its hard
// limit if allowed, less a margin for everything else).
std::uint32_t connection_budget();

}  // namespace mbstorm::netfuzz
