// Human-friendly number formatting shared by the console and HTML reports.
#pragma once

#include <chrono>
#include <cstdint>
#include <string>

namespace mbstorm::report {

// Three significant digits with a unit picked by size: "850ns", "812µs", "1.23ms", "2.50s".
std::string format_latency(std::uint64_t ns);
// Same, from a floating-point ns value (means, standard deviations).
std::string format_latency(double ns);
// "850", "48.2k", "1.23M".
std::string format_rate(double per_second);
// "512 B", "12.3 KiB", "4.56 MiB", "1.20 GiB".
std::string format_bytes(std::uint64_t bytes);
// "10.0s", "2m05s", "1h02m".
std::string format_duration(std::uint64_t ns);
// "1,234,567".
std::string format_count(std::uint64_t n);
// ISO 8601 UTC, e.g. "2024-05-01T12:00:00Z"; "" for the epoch (unset).
std::string format_utc(std::chrono::system_clock::time_point t);
// "0x02".
std::string format_hex_byte(std::uint8_t b);
// How reports name an operation: "poll (0x03 read_holding_registers)", or only the function
// label when the operation is named after its function.
std::string format_operation(const std::string& name, std::uint8_t function_code);
// "0x02 ILLEGAL DATA ADDRESS" for the codes the specification names, else "0x2A".
std::string format_exception_code(std::uint8_t code);

}  // namespace mbstorm::report
