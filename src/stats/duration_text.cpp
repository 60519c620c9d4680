#include "stats/duration_text.hpp"

#include <charconv>
#include <cmath>

namespace mbstorm::stats {

namespace {

// Nanoseconds per unit, or 0 for an unknown unit.
double unit_scale(std::string_view unit) noexcept {
    if (unit == "ns") return 1;
    if (unit == "us" || unit == "\xC2\xB5s") return 1e3;
    if (unit == "ms") return 1e6;
    if (unit == "s") return 1e9;
    if (unit == "m" || unit == "min") return 60e9;
    if (unit == "h") return 3600e9;
    return 0;
}

bool is_number_char(char c) noexcept {
    return (c >= '0' && c <= '9') || c == '.';
}

}  // namespace

bool parse_duration_ns(std::string_view text, std::uint64_t& out_ns,
                       std::uint64_t default_unit_ns) noexcept {
    while (!text.empty() && text.front() == ' ') text.remove_prefix(1);
    while (!text.empty() && text.back() == ' ') text.remove_suffix(1);
    if (text.empty()) return false;
    // One or more "<number><unit>" parts ("1m30s", "1h2m", "1.5s"); a lone bare number is
    // taken in the default unit. Letters only, so "nan" and "inf" are never numbers here.
    double total = 0;
    std::size_t parts = 0;
    while (!text.empty()) {
        std::size_t digits = 0;
        while (digits < text.size() && is_number_char(text[digits])) ++digits;
        if (digits == 0) return false;
        double number = 0;
        auto [end, ec] = std::from_chars(text.data(), text.data() + digits, number);
        if (ec != std::errc() || end != text.data() + digits || !std::isfinite(number))
            return false;
        text.remove_prefix(digits);
        std::size_t space = 0;
        while (space < text.size() && text[space] == ' ') ++space;
        std::size_t letters = space;
        while (letters < text.size() && !is_number_char(text[letters]) && text[letters] != ' ')
            ++letters;
        const std::string_view unit = text.substr(space, letters - space);
        double scale;
        if (unit.empty()) {
            // A bare number only on its own: "1m30" is a mistake, not 1 min 30 s.
            if (parts != 0 || letters != text.size()) return false;
            scale = static_cast<double>(default_unit_ns);
        } else {
            scale = unit_scale(unit);
            if (scale == 0) return false;
        }
        text.remove_prefix(letters);
        while (!text.empty() && text.front() == ' ') text.remove_prefix(1);
        total += number * scale;
        ++parts;
    }
    if (!(total <= 1.8e19)) return false;
    out_ns = static_cast<std::uint64_t>(std::llround(total));
    return true;
}

}  // namespace mbstorm::stats
