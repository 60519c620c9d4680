#include <charconv>

#include "server/tls_link.hpp"

namespace mbstorm::server {

namespace {

bool parse_code(std::string_view text, unsigned& out) {
    int base = 10;
    if (text.size() > 2 && text[0] == '0' && (text[1] == 'x' || text[1] == 'X')) {
        text.remove_prefix(2);
        base = 16;
    }
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), out, base);
    return ec == std::errc() && end == text.data() + text.size() && out >= 1 && out <= 255;
}

}  // namespace

bool TlsRoles::add_rule(std::string_view text, std::string& error) {
    const std::size_t eq = text.find('=');
    if (eq == std::string_view::npos || eq == 0 || eq + 1 == text.size()) {
        error = "a role rule is ROLE=FC,FC-FC,... (for example Operator=1-6,15,16)";
        return false;
    }
    FunctionSet set;
    std::string_view list = text.substr(eq + 1);
    while (!list.empty()) {
        const std::size_t comma = list.find(',');
        const std::string_view item = list.substr(0, comma);
        list = comma == std::string_view::npos ? std::string_view() : list.substr(comma + 1);
        const std::size_t dash = item.find('-');
        unsigned low = 0, high = 0;
        const bool ok = dash == std::string_view::npos
                            ? parse_code(item, low) && ((high = low), true)
                            : parse_code(item.substr(0, dash), low) &&
                                  parse_code(item.substr(dash + 1), high) && low <= high;
        if (!ok) {
            error = "bad function code or range '" + std::string(item) + "' in role rule '" +
                    std::string(text) + "' (codes 1..255)";
            return false;
        }
        for (unsigned fc = low; fc <= high; ++fc) set.set(fc);
    }
    allow(std::string(text.substr(0, eq)), set);
    return true;
}

void TlsRoles::allow(std::string role, const FunctionSet& functions) {
    for (auto& [name, set] : roles_) {
        if (name == role) {
            set |= functions;
            return;
        }
    }
    roles_.emplace_back(std::move(role), functions);
}

const FunctionSet* TlsRoles::allowed_for(std::string_view role) const noexcept {
    if (roles_.empty()) return nullptr;
    static const FunctionSet kNothing;
    for (const auto& [name, set] : roles_)
        if (name == role) return &set;
    return &kNothing;
}

}  // namespace mbstorm::server
