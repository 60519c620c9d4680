// Per-operation read-back checks (`expect:`): the values a read returns must equal a value,
// lie in a range, or match a list indexed by address. A failed check is counted by the
// engine as Outcome::ValueMismatch (an error).
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "load/engine.hpp"

namespace mbstorm::scenario {

struct Expectation {
    bool active = false;
    std::optional<std::uint16_t> value;  // every item read equals this
    std::optional<std::uint16_t> min;    // every item read is >= min
    std::optional<std::uint16_t> max;    // ... and <= max
    // Item at address A equals values[A - first_address] (covers the operation's range).
    std::vector<std::uint16_t> values;
    std::uint16_t first_address = 0;
    bool operator==(const Expectation&) const = default;
};

// True when the function returns data an expectation can check (FC01-04, 17).
bool can_expect(std::uint8_t function) noexcept;

// Verifier for load::EngineOptions; `expectations` (one per operation, by index) must outlive
// the run. Thread-safe, allocation-free.
load::ResponseVerifier make_verifier(const std::vector<Expectation>& expectations) noexcept;

// The check itself (exposed for tests).
bool response_matches(const Expectation& expectation, const load::RequestInfo& request,
                      const codec::Response& response) noexcept;

}  // namespace mbstorm::scenario
