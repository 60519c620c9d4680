#include "netfuzz/dictionary.hpp"

#include <fmt/format.h>

#include <cctype>
#include <charconv>
#include <fstream>
#include <sstream>

namespace mbstorm::netfuzz {
namespace {

constexpr std::size_t kMaxEntries = 65536;
constexpr std::size_t kMaxToken = 253;  // a whole PDU

int hex_digit(char c) {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return -1;
}

std::string trim(const std::string& s) {
    std::size_t a = 0, b = s.size();
    while (a < b && std::isspace(static_cast<unsigned char>(s[a]))) ++a;
    while (b > a && std::isspace(static_cast<unsigned char>(s[b - 1]))) --b;
    return s.substr(a, b - a);
}

// A bare number: decimal or 0x hex, 0..0xFFFF.
bool parse_word(const std::string& s, std::uint16_t& out) {
    const bool hex = s.size() > 2 && s[0] == '0' && (s[1] == 'x' || s[1] == 'X');
    const char* first = s.data() + (hex ? 2 : 0);
    unsigned long v = 0;
    const auto [end, ec] = std::from_chars(first, s.data() + s.size(), v, hex ? 16 : 10);
    if (ec != std::errc() || end != s.data() + s.size() || v > 0xFFFF) return false;
    out = static_cast<std::uint16_t>(v);
    return true;
}

// The quoted part of `"..."`, escapes resolved. Empty `why` on success.
std::vector<std::uint8_t> unquote(const std::string& s, std::string& why) {
    std::vector<std::uint8_t> out;
    if (s.size() < 2 || s.front() != '"' || s.back() != '"') {
        why = "expected a quoted value, name=\"...\" or \"...\"";
        return out;
    }
    for (std::size_t i = 1; i + 1 < s.size(); ++i) {
        const char c = s[i];
        if (c != '\\') {
            out.push_back(static_cast<std::uint8_t>(c));
            continue;
        }
        if (i + 2 >= s.size()) {
            why = "a backslash at the end of the value";
            return out;
        }
        const char e = s[++i];
        if (e == '\\' || e == '"') {
            out.push_back(static_cast<std::uint8_t>(e));
        } else if (e == 'x' && i + 2 < s.size() && hex_digit(s[i + 1]) >= 0 &&
                   hex_digit(s[i + 2]) >= 0) {
            out.push_back(
                static_cast<std::uint8_t>(hex_digit(s[i + 1]) << 4 | hex_digit(s[i + 2])));
            i += 2;
        } else {
            why = fmt::format("unknown escape \\{} (use \\xHH, \\\\ or \\\")", e);
            return out;
        }
    }
    if (out.empty()) why = "an empty value";
    if (out.size() > kMaxToken)
        why = fmt::format("a value of {} bytes (at most {})", out.size(), kMaxToken);
    return out;
}

}  // namespace

Result<Dictionary> parse_dictionary(const std::string& text, const std::string& name) {
    Dictionary out;
    std::istringstream in(text);
    std::string line;
    for (std::size_t n = 1; std::getline(in, line); ++n) {
        const std::string t = trim(line);
        if (t.empty() || t[0] == '#') continue;
        const std::string place = fmt::format("{}:{}", name, n);
        if (out.words.size() + out.tokens.size() >= kMaxEntries) {
            return Error(ErrorCode::InvalidInput, fmt::format("more than {} entries", kMaxEntries),
                         place);
        }
        std::uint16_t w = 0;
        if (parse_word(t, w)) {
            out.words.push_back(w);
            continue;
        }
        const auto q = t.find('"');
        std::string value = q == std::string::npos ? t : t.substr(q);
        if (q != std::string::npos && q > 0 && trim(t.substr(0, q)).back() != '=')
            return Error(ErrorCode::InvalidInput, "expected name=\"value\"", place);
        std::string why;
        const auto bytes = unquote(value, why);
        if (!why.empty()) return Error(ErrorCode::InvalidInput, why, place);
        if (bytes.size() == 2)
            out.words.push_back(static_cast<std::uint16_t>(bytes[0] << 8 | bytes[1]));
        else
            out.tokens.push_back(bytes);
    }
    return out;
}

Result<Dictionary> load_dictionary(const std::string& path) {
    std::ifstream f(path, std::ios::binary);
    if (!f) return Error(open_failure(path), fmt::format("cannot read --dict {}", path));
    std::ostringstream all;
    all << f.rdbuf();
    if (all.str().size() > 16u << 20)
        return Error(ErrorCode::InvalidInput, fmt::format("--dict {}: larger than 16 MiB", path));
    return parse_dictionary(all.str(), path);
}

}  // namespace mbstorm::netfuzz
