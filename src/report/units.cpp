#include "report/units.hpp"

#include "codec/exception_code.hpp"
#include "codec/function_code.hpp"

#include <fmt/chrono.h>
#include <fmt/format.h>

#include <cmath>
#include <ctime>

namespace mbstorm::report {
namespace {

// Three significant digits: 1.23, 12.3, 123.
std::string three_digits(double v, const char* unit) {
    if (v < 9.995) return fmt::format("{:.2f}{}", v, unit);
    if (v < 99.95) return fmt::format("{:.1f}{}", v, unit);
    return fmt::format("{:.0f}{}", v, unit);
}

}  // namespace

std::string format_latency(double ns) {
    if (!(ns >= 0.0)) return "-";
    if (ns < 999.5) return fmt::format("{:.0f}ns", ns);
    if (ns < 999.5e3) return three_digits(ns / 1e3, "µs");
    if (ns < 999.5e6) return three_digits(ns / 1e6, "ms");
    return three_digits(ns / 1e9, "s");
}

std::string format_latency(std::uint64_t ns) {
    return format_latency(static_cast<double>(ns));
}

std::string format_rate(double per_second) {
    if (!(per_second >= 0.0)) return "-";
    if (per_second < 999.5) return fmt::format("{:.0f}", per_second);
    if (per_second < 999.5e3) return three_digits(per_second / 1e3, "k");
    return three_digits(per_second / 1e6, "M");
}

std::string format_bytes(std::uint64_t bytes) {
    const double b = static_cast<double>(bytes);
    if (bytes < 1024) return fmt::format("{} B", bytes);
    if (b < 1024.0 * 1024) return three_digits(b / 1024, " KiB");
    if (b < 1024.0 * 1024 * 1024) return three_digits(b / (1024.0 * 1024), " MiB");
    return three_digits(b / (1024.0 * 1024 * 1024), " GiB");
}

std::string format_duration(std::uint64_t ns) {
    const double s = static_cast<double>(ns) / 1e9;
    if (s < 60.0) return fmt::format("{:.1f}s", s);
    const auto total = static_cast<std::uint64_t>(std::llround(s));
    if (total < 3600) return fmt::format("{}m{:02}s", total / 60, total % 60);
    return fmt::format("{}h{:02}m", total / 3600, (total % 3600) / 60);
}

std::string format_count(std::uint64_t n) {
    std::string digits = std::to_string(n);
    std::string out;
    const std::size_t lead = digits.size() % 3;
    for (std::size_t i = 0; i < digits.size(); ++i) {
        if (i != 0 && (i % 3) == lead % 3) out.push_back(',');
        out.push_back(digits[i]);
    }
    return out;
}

std::string format_utc(std::chrono::system_clock::time_point t) {
    if (t.time_since_epoch().count() == 0) return "";
    const std::time_t seconds = std::chrono::system_clock::to_time_t(t);
    std::tm tm{};
    gmtime_r(&seconds, &tm);
    return fmt::format("{:%Y-%m-%dT%H:%M:%SZ}", tm);
}

std::string format_exception_code(std::uint8_t code) {
    if (!codec::is_known_exception(code)) return format_hex_byte(code);
    return fmt::format("0x{:02X} {}", code,
                       codec::exception_name(static_cast<codec::ExceptionCode>(code)));
}

std::string format_operation(const std::string& name, std::uint8_t function_code) {
    std::string label = codec::function_label(function_code);
    if (name.empty() || name == codec::function_name(function_code)) return label;
    return fmt::format("{} ({})", name, label);
}

std::string format_hex_byte(std::uint8_t b) {
    return fmt::format("0x{:02X}", b);
}

}  // namespace mbstorm::report
