#include "load/foreign_protocol.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <string_view>

namespace mbstorm::load {
namespace {

bool starts_with(codec::Bytes b, std::string_view text) {
    return b.size() >= text.size() && std::equal(text.begin(), text.end(), b.begin());
}

// An HTML page, as an HTTP server sends to a request it cannot parse as HTTP at all
// (`python3 -m http.server` answers a Modbus request with one, without a status line).
bool starts_like_html(codec::Bytes b) {
    std::string head;
    for (const std::uint8_t x : b.first(std::min<std::size_t>(b.size(), 9)))
        head += static_cast<char>(std::tolower(x));
    return head.rfind("<!doctype", 0) == 0 || head.rfind("<html", 0) == 0;
}

std::string hex_of(codec::Bytes b) {
    std::string s;
    for (const std::uint8_t x : b) s += fmt::format("{}{:02X}", s.empty() ? "" : " ", x);
    return s;
}

// The sample as text when it is printable (line ends shown as spaces), else empty.
std::string text_of(codec::Bytes b) {
    std::string s;
    for (const std::uint8_t x : b) {
        if (x == '\r' || x == '\n') {
            s += ' ';
        } else if (std::isprint(x)) {
            s += static_cast<char>(x);
        } else {
            return {};
        }
    }
    return s;
}

}  // namespace

std::string describe_foreign_bytes(codec::Bytes sample) {
    if (sample.empty()) return {};
    const std::string text = text_of(sample);
    const std::string shown = text.empty() ? hex_of(sample) : fmt::format("\"{}\"", text);
    if (starts_with(sample, "HTTP/") || starts_like_html(sample))
        return fmt::format("an HTTP server ({})", shown);
    if (starts_with(sample, "SSH-")) return fmt::format("an SSH server ({})", shown);
    // A TLS record: handshake (22) or alert (21), version 3.x.
    if (sample.size() >= 3 && (sample[0] == 22 || sample[0] == 21) && sample[1] == 3)
        return fmt::format("a TLS server: try --transport tls ({})", shown);
    if (!text.empty()) return fmt::format("a text protocol ({})", shown);
    return fmt::format("not Modbus/TCP ({})", shown);
}

}  // namespace mbstorm::load
