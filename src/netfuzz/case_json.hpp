// Cases in the files a user hands us back (finding.json, corpus entries): the steps as JSON and
// back, and every number read as a whole number in its field's range or an error, never a
// conversion of what does not fit (a float or an out-of-range value cast to a narrower type
// is undefined behaviour).
#pragma once

#include <fmt/format.h>

#include <cstdint>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "netfuzz/case.hpp"

namespace mbstorm::netfuzz {

// `v` as a whole number in [lo, hi]; throws std::runtime_error naming `what` otherwise.
inline std::int64_t whole_number(const nlohmann::json& v, const char* what, std::int64_t lo,
                                 std::int64_t hi) {
    const bool whole =
        v.is_number_integer() &&
        (v.is_number_unsigned() ? v.get<std::uint64_t>() <= std::uint64_t(hi)
                                : v.get<std::int64_t>() >= lo && v.get<std::int64_t>() <= hi);
    if (!whole || v.get<std::int64_t>() < lo)
        throw std::runtime_error(
            fmt::format("'{}' is not a whole number from {} to {}", what, lo, hi));
    return v.get<std::int64_t>();
}

// j[key] as above, or `fallback` when j has no such key.
inline std::int64_t whole_number(const nlohmann::json& j, const char* key, std::int64_t fallback,
                                 std::int64_t lo, std::int64_t hi) {
    return j.contains(key) ? whole_number(j.at(key), key, lo, hi) : fallback;
}

// A case's steps: [{"op", "conn", "delay_us", "count", "hex"}, ...].
nlohmann::json steps_to_json(const Case& c);
// Appends the steps to `c`; throws std::runtime_error on anything out of place, or past
// `max_steps` steps.
void steps_from_json(const nlohmann::json& steps, Case& c, std::size_t max_steps);

}  // namespace mbstorm::netfuzz
