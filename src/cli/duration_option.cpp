#include "cli/duration_option.hpp"

#include <fmt/format.h>

#include <charconv>
#include <cmath>

#include "stats/duration_text.hpp"

namespace mbstorm::cli {

namespace {

// "1000000000" -> "1,000,000,000"; "0.5" stays "0.5".
std::string number_words(double v) {
    if (v == std::floor(v) && std::fabs(v) < 1e15) {
        std::string digits = fmt::format("{:.0f}", std::fabs(v));
        std::string out;
        for (std::size_t i = 0; i < digits.size(); ++i) {
            if (i != 0 && (digits.size() - i) % 3 == 0) out += ',';
            out += digits[i];
        }
        return v < 0 ? "-" + out : out;
    }
    return fmt::format("{}", v);
}

}  // namespace

CLI::Option* add_duration_option(CLI::App* cmd, const std::string& name, std::uint64_t& ns,
                                 const std::string& description) {
    return cmd
        ->add_option_function<std::string>(
            name,
            [&ns, name](const std::string& text) {
                if (!stats::parse_duration_ns(text, ns))
                    throw CLI::ValidationError(
                        name,
                        "'" + text +
                            "' is not a duration (e.g. 500ms, 1.5s, 1m30s, 1h2m; a bare number is "
                            "seconds)");
            },
            description)
        ->type_name("DURATION");
}

CLI::Option* add_rate_option(CLI::App* cmd, const std::string& name, double& fraction,
                             const std::string& description) {
    return cmd
        ->add_option_function<std::string>(
            name,
            [&fraction, name](const std::string& text) {
                std::string t = text;
                bool percent = !t.empty() && t.back() == '%';
                if (percent) t.pop_back();
                double v = -1;
                try {
                    std::size_t used = 0;
                    v = std::stod(t, &used);
                    if (used != t.size()) v = -1;
                } catch (...) {
                    v = -1;
                }
                if (percent) v /= 100.0;
                if (!(v >= 0.0 && v <= 1.0))
                    throw CLI::ValidationError(
                        name, "'" + text + "' is not a rate in 0..1 (e.g. 0.01 or 1%)");
                fraction = v;
            },
            description)
        ->type_name("RATE");
}

CLI::Option* add_number_option(CLI::App* cmd, const std::string& name, double& value, double min,
                               double max, const std::string& description) {
    const std::string range = "a number from " + number_words(min) + " to " + number_words(max);
    return cmd
        ->add_option_function<std::string>(
            name,
            [&value, name, min, max, range](const std::string& text) {
                double v = 0;
                auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
                // from_chars reads "nan" and "inf": finiteness is checked, not assumed.
                if (ec != std::errc() || end != text.data() + text.size() || !std::isfinite(v) ||
                    v < min || v > max)
                    throw CLI::ValidationError(name, "'" + text + "' is not " + range);
                value = v;
            },
            description + " (" + range + ")")
        ->type_name("NUMBER");
}

CLI::Option* add_count_option(CLI::App* cmd, const std::string& name, std::uint64_t& value,
                              const std::string& description, std::uint64_t min) {
    return cmd
        ->add_option_function<std::string>(
            name,
            [&value, name, min](const std::string& text) {
                std::uint64_t v = 0;
                auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
                if (ec != std::errc() || end != text.data() + text.size() || v < min)
                    throw CLI::ValidationError(
                        name, min == 0 ? fmt::format("'{}' is not a whole number", text)
                                       : fmt::format("'{}' is not a whole number of at least {}",
                                                     text, min));
                value = v;
            },
            description)
        ->type_name("COUNT");
}

}  // namespace mbstorm::cli
