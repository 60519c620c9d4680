#include "stats/duration_text.hpp"

#include <charconv>
#include <cmath>

namespace mbstorm::stats {

bool parse_duration_ns(std::string_view text, std::uint64_t& out_ns,
                       std::uint64_t default_unit_ns) noexcept {
    while (!text.empty() && text.front() == ' ') text.remove_prefix(1);
    while (!text.empty() && text.back() == ' ') text.remove_suffix(1);
    std::size_t digits = 0;
    while (digits < text.size() &&
           ((text[digits] >= '0' && text[digits] <= '9') || text[digits] == '.'))
        ++digits;
    if (digits == 0) return false;
    double number = 0;
    auto [end, ec] = std::from_chars(text.data(), text.data() + digits, number);
    if (ec != std::errc() || end != text.data() + digits || !std::isfinite(number) || number < 0)
        return false;
    std::string_view unit = text.substr(digits);
    while (!unit.empty() && unit.front() == ' ') unit.remove_prefix(1);
    double scale;
    if (unit.empty())
        scale = static_cast<double>(default_unit_ns);
    else if (unit == "ns")
        scale = 1;
    else if (unit == "us" || unit == "\xC2\xB5s")
        scale = 1e3;
    else if (unit == "ms")
        scale = 1e6;
    else if (unit == "s")
        scale = 1e9;
    else if (unit == "m" || unit == "min")
        scale = 60e9;
    else if (unit == "h")
        scale = 3600e9;
    else
        return false;
    double ns = number * scale;
    if (ns > 1.8e19) return false;
    out_ns = static_cast<std::uint64_t>(std::llround(ns));
    return true;
}

}  // namespace mbstorm::stats
