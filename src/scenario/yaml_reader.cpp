#include "scenario/yaml_reader.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <set>

#include "scenario/scenario.hpp"
#include "stats/duration_text.hpp"

namespace mbstorm::scenario {

void YamlReader::fail(const YAML::Mark& mark, const std::string& message) const {
    const int line = mark.is_null() ? 0 : mark.line + 1;
    const int column = mark.is_null() ? 0 : mark.column + 1;
    std::string text = source_;
    if (line > 0) text += fmt::format(":{}:{}", line, column);
    throw ScenarioError(text + ": " + message, line, column);
}

std::string YamlReader::where(const YAML::Node& node) const {
    const YAML::Mark m = node.Mark();
    if (m.is_null()) return source_;
    return fmt::format("{}:{}:{}", source_, m.line + 1, m.column + 1);
}

void YamlReader::each_key(
    const YAML::Node& map, std::string_view what, std::initializer_list<std::string_view> known,
    const std::function<void(const std::string&, const YAML::Node&, const YAML::Node&)>& f) const {
    if (!map.IsMap()) fail(map, fmt::format("{} must be a mapping of keys to values", what));
    std::set<std::string> seen;
    for (const auto& kv : map) {
        if (!kv.first.IsScalar()) fail(kv.first, fmt::format("{}: keys must be plain words", what));
        const std::string key = kv.first.Scalar();
        if (std::find(known.begin(), known.end(), key) == known.end()) {
            fail(kv.first, fmt::format("unknown key '{}' in {} (valid keys: {})", key, what,
                                       fmt::join(known, ", ")));
        }
        if (!seen.insert(key).second) {
            fail(kv.first, fmt::format("duplicate key '{}' in {}", key, what));
        }
        f(key, kv.first, kv.second);
    }
}

std::string YamlReader::scalar(const YAML::Node& n, std::string_view what) const {
    if (!n.IsScalar())
        fail(n, fmt::format("{} must be a single value, not a list or mapping", what));
    return n.Scalar();
}

bool YamlReader::parse_integer(std::string_view s, std::int64_t& out) {
    const char* p = s.data();
    const char* end = p + s.size();
    bool negative = false;
    if (p != end && (*p == '-' || *p == '+')) negative = *p++ == '-';
    int base = 10;
    if (end - p > 2 && p[0] == '0' && (p[1] == 'x' || p[1] == 'X')) {
        base = 16;
        p += 2;
    }
    if (p == end) return false;
    std::uint64_t magnitude = 0;
    const auto [ptr, ec] = std::from_chars(p, end, magnitude, base);
    if (ec != std::errc() || ptr != end || magnitude > (1ULL << 62)) return false;
    out = negative ? -static_cast<std::int64_t>(magnitude) : static_cast<std::int64_t>(magnitude);
    return true;
}

std::int64_t YamlReader::integer(const YAML::Node& n, std::string_view what, std::int64_t lo,
                                 std::int64_t hi) const {
    const std::string s = scalar(n, what);
    std::int64_t v = 0;
    if (!parse_integer(s, v)) {
        fail(n, fmt::format("{}: '{}' is not a whole number (valid {}..{})", what, s, lo, hi));
    }
    if (v < lo || v > hi) {
        fail(n, fmt::format("{}: {} is out of range (valid {}..{})", what, s, lo, hi));
    }
    return v;
}

double YamlReader::number(const YAML::Node& n, std::string_view what, double lo, double hi) const {
    const std::string s = scalar(n, what);
    double v = 0;
    std::int64_t i = 0;
    if (parse_integer(s, i)) {
        v = static_cast<double>(i);
    } else {
        const char* first = s.data();
        if (!s.empty() && *first == '+') ++first;
        const auto [ptr, ec] = std::from_chars(first, s.data() + s.size(), v);
        if (s.empty() || ec != std::errc() || ptr != s.data() + s.size() || !std::isfinite(v)) {
            fail(n, fmt::format("{}: '{}' is not a number (valid {:g}..{:g})", what, s, lo, hi));
        }
    }
    if (v < lo || v > hi) {
        fail(n, fmt::format("{}: {} is out of range (valid {:g}..{:g})", what, s, lo, hi));
    }
    return v;
}

bool YamlReader::boolean(const YAML::Node& n, std::string_view what) const {
    const std::string s = scalar(n, what);
    if (s == "true" || s == "yes" || s == "on") return true;
    if (s == "false" || s == "no" || s == "off") return false;
    fail(n, fmt::format("{}: '{}' is not true or false", what, s));
}

load::Duration YamlReader::duration(const YAML::Node& n, std::string_view what, load::Duration lo,
                                    load::Duration hi, bool lo_exclusive) const {
    const std::string s = scalar(n, what);
    const std::string range =
        hi.count() > 0 ? fmt::format("valid {}{}..{}", lo_exclusive ? "> " : "", duration_text(lo),
                                     duration_text(hi))
                       : fmt::format("valid {} {}", lo_exclusive ? ">" : ">=", duration_text(lo));
    std::uint64_t ns = 0;
    if (!stats::parse_duration_ns(s, ns) || ns > static_cast<std::uint64_t>(INT64_MAX)) {
        fail(n, fmt::format("{}: '{}' is not a duration (e.g. 500ms, 10s, 1m30s; a bare number is "
                            "seconds; {})",
                            what, s, range));
    }
    const load::Duration d{static_cast<std::int64_t>(ns)};
    if (d < lo || (lo_exclusive && d == lo) || (hi.count() > 0 && d > hi)) {
        fail(n, fmt::format("{}: {} is out of range ({})", what, s, range));
    }
    return d;
}

std::string YamlReader::choice(const YAML::Node& n, std::string_view what,
                               std::initializer_list<std::string_view> choices) const {
    const std::string s = scalar(n, what);
    if (std::find(choices.begin(), choices.end(), s) == choices.end()) {
        fail(n, fmt::format("{}: '{}' is not one of {}", what, s, fmt::join(choices, ", ")));
    }
    return s;
}

std::string duration_text(load::Duration d) {
    const std::int64_t ns = d.count();
    if (ns == 0) return "0s";
    if (ns % 3'600'000'000'000 == 0) return fmt::format("{}h", ns / 3'600'000'000'000);
    if (ns % 60'000'000'000 == 0) return fmt::format("{}m", ns / 60'000'000'000);
    if (ns % 1'000'000'000 == 0) return fmt::format("{}s", ns / 1'000'000'000);
    if (ns % 1'000'000 == 0) return fmt::format("{}ms", ns / 1'000'000);
    if (ns % 1'000 == 0) return fmt::format("{}us", ns / 1'000);
    return fmt::format("{}ns", ns);
}

}  // namespace mbstorm::scenario
