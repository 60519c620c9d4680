// Durations as people write them on command lines and in YAML: "250us", "2ms", "1.5s", "2m",
// "1h" and compounds of them ("1m30s", "1h2m", "1s500ms"). A bare number alone is taken in
// `default_unit_ns` (seconds unless said otherwise).
#pragma once

#include <cstdint>
#include <string_view>

namespace mbstorm::stats {

// False when the text is not one non-negative number with an optional unit or a sequence of
// numbers each with a unit (ns, us, µs, ms, s, m, min, h); NaN and infinity are never durations.
bool parse_duration_ns(std::string_view text, std::uint64_t& out_ns,
                       std::uint64_t default_unit_ns = 1'000'000'000ULL) noexcept;

}  // namespace mbstorm::stats
