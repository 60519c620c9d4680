#include "yaml/reader.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <set>
#include <stdexcept>

#include "util/closest_name.hpp"

namespace mbstorm::yaml {
namespace {

// Well-formed UTF-8: no stray continuation bytes, overlong forms, surrogates or code points
// past U+10FFFF.
bool is_utf8(std::string_view s) noexcept {
    for (std::size_t i = 0; i < s.size();) {
        const auto b = static_cast<unsigned char>(s[i]);
        std::size_t n = 0;
        std::uint32_t cp = 0;
        if (b < 0x80) {
            ++i;
            continue;
        } else if (b >= 0xC2 && b <= 0xDF) {
            n = 1, cp = b & 0x1Fu;
        } else if (b >= 0xE0 && b <= 0xEF) {
            n = 2, cp = b & 0x0Fu;
        } else if (b >= 0xF0 && b <= 0xF4) {
            n = 3, cp = b & 0x07u;
        } else {
            return false;
        }
        if (s.size() - i <= n) return false;
        for (std::size_t k = 1; k <= n; ++k) {
            const auto c = static_cast<unsigned char>(s[i + k]);
            if ((c & 0xC0) != 0x80) return false;
            cp = (cp << 6) | (c & 0x3Fu);
        }
        const std::uint32_t least = n == 2 ? 0x800 : n == 3 ? 0x10000 : 0x80;
        if (cp < least || cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF)) return false;
        i += n + 1;
    }
    return true;
}

}  // namespace

void Reader::fail(const YAML::Mark& mark, const std::string& message) const {
    const int line = mark.is_null() ? 0 : mark.line + 1;
    const int column = mark.is_null() ? 0 : mark.column + 1;
    std::string text = source_;
    if (line > 0) text += fmt::format(":{}:{}", line, column);
    raise_(text + ": " + message, line, column);
    // A RaiseError that returns is a programming error; never continue past a failure.
    throw std::logic_error(text + ": " + message);
}

std::string Reader::where(const YAML::Node& node) const {
    const YAML::Mark m = node.Mark();
    if (m.is_null()) return source_;
    return fmt::format("{}:{}:{}", source_, m.line + 1, m.column + 1);
}

void Reader::each_key(const YAML::Node& map, std::string_view what,
                      std::span<const std::string_view> known, const KeyVisitor& f) const {
    if (!map.IsMap()) fail(map, fmt::format("{} must be a mapping of keys to values", what));
    std::set<std::string> seen;
    for (const auto& kv : map) {
        if (!kv.first.IsScalar()) fail(kv.first, fmt::format("{}: keys must be plain words", what));
        const std::string key = kv.first.Scalar();
        if (std::find(known.begin(), known.end(), key) == known.end()) {
            // A typo gets its one fix; anything else the whole list to choose from.
            const std::string_view closest = util::closest_name(key, known);
            fail(kv.first, closest.empty()
                               ? fmt::format("unknown key '{}' in {} (valid keys: {})", key, what,
                                             fmt::join(known, ", "))
                               : fmt::format("unknown key '{}' in {}; did you mean '{}'?", key,
                                             what, closest));
        }
        if (!seen.insert(key).second) {
            fail(kv.first, fmt::format("duplicate key '{}' in {}", key, what));
        }
        f(key, kv.first, kv.second);
    }
}

std::string Reader::scalar(const YAML::Node& n, std::string_view what) const {
    if (!n.IsScalar())
        fail(n, fmt::format("{} must be a single value, not a list or mapping", what));
    // The printers (run --print-scenario, the device print) write through yaml-cpp's emitter,
    // which turns bytes that are not UTF-8 into U+FFFD: such text would not read back as given.
    if (!is_utf8(n.Scalar())) fail(n, fmt::format("{} is not UTF-8 text", what));
    return n.Scalar();
}

bool Reader::parse_integer(std::string_view s, std::int64_t& out) {
    const char* p = s.data();
    const char* end = p + s.size();
    bool negative = false;
    if (p != end && (*p == '-' || *p == '+')) negative = *p++ == '-';
    int base = 10;
    if (end - p > 2 && p[0] == '0' && (p[1] == 'x' || p[1] == 'X')) {
        base = 16;
        p += 2;
    } else if (end - p > 2 && p[0] == '0' && (p[1] == 'b' || p[1] == 'B')) {
        base = 2;
        p += 2;
    }
    if (p == end) return false;
    std::uint64_t magnitude = 0;
    const auto [ptr, ec] = std::from_chars(p, end, magnitude, base);
    if (ec != std::errc() || ptr != end || magnitude > (1ULL << 62)) return false;
    out = negative ? -static_cast<std::int64_t>(magnitude) : static_cast<std::int64_t>(magnitude);
    return true;
}

std::int64_t Reader::integer(const YAML::Node& n, std::string_view what, std::int64_t lo,
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

namespace {

bool parse_number(const std::string& s, double& out) {
    std::int64_t i = 0;
    if (Reader::parse_integer(s, i)) {
        out = static_cast<double>(i);
        return true;
    }
    const char* first = s.data();
    const char* last = s.data() + s.size();
    if (first != last && *first == '+') ++first;
    const auto [ptr, ec] = std::from_chars(first, last, out);
    return !s.empty() && ec == std::errc() && ptr == last && std::isfinite(out);
}

}  // namespace

double Reader::number(const YAML::Node& n, std::string_view what) const {
    const std::string s = scalar(n, what);
    double v = 0;
    if (!parse_number(s, v)) fail(n, fmt::format("{}: '{}' is not a number", what, s));
    return v;
}

double Reader::number(const YAML::Node& n, std::string_view what, double lo, double hi) const {
    const std::string s = scalar(n, what);
    double v = 0;
    if (!parse_number(s, v)) {
        fail(n, fmt::format("{}: '{}' is not a number (valid {:g}..{:g})", what, s, lo, hi));
    }
    if (v < lo || v > hi) {
        fail(n, fmt::format("{}: {} is out of range (valid {:g}..{:g})", what, s, lo, hi));
    }
    return v;
}

bool Reader::boolean(const YAML::Node& n, std::string_view what) const {
    const std::string s = scalar(n, what);
    std::string lower = s;
    std::transform(lower.begin(), lower.end(), lower.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (lower == "true" || lower == "yes" || lower == "on") return true;
    if (lower == "false" || lower == "no" || lower == "off") return false;
    fail(n, fmt::format("{}: '{}' is not true or false", what, s));
}

std::string Reader::choice(const YAML::Node& n, std::string_view what,
                           std::initializer_list<std::string_view> choices) const {
    const std::string s = scalar(n, what);
    if (std::find(choices.begin(), choices.end(), s) == choices.end()) {
        fail(n, fmt::format("{}: '{}' is not one of {}", what, s, fmt::join(choices, ", ")));
    }
    return s;
}

}  // namespace mbstorm::yaml
