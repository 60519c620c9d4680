#include "codec/function_set.hpp"

#include <charconv>

namespace mbstorm::codec {
namespace {

bool parse_code_byte(std::string_view text, unsigned& out) {
    int base = 10;
    if (text.size() > 2 && text[0] == '0' && (text[1] == 'x' || text[1] == 'X')) {
        text.remove_prefix(2);
        base = 16;
    }
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), out, base);
    return !text.empty() && ec == std::errc() && end == text.data() + text.size() && out >= 1 &&
           out <= 255;
}

}  // namespace

std::string parse_function_set(std::string_view list, FunctionSet& out) {
    out.reset();
    if (list.empty()) return "an empty list of function codes";
    const std::string_view whole = list;
    for (;;) {
        const std::size_t comma = list.find(',');
        const std::string_view item = list.substr(0, comma);
        const std::size_t dash = item.find('-');
        unsigned low = 0, high = 0;
        const bool ok = dash == std::string_view::npos
                            ? parse_code_byte(item, low) && ((high = low), true)
                            : parse_code_byte(item.substr(0, dash), low) &&
                                  parse_code_byte(item.substr(dash + 1), high) && low <= high;
        if (!ok)
            return "bad function code or range '" + std::string(item) + "' in '" +
                   std::string(whole) + "' (codes 1..255, decimal or 0x hex, ranges like 1-6)";
        for (unsigned fc = low; fc <= high; ++fc) out.set(fc);
        if (comma == std::string_view::npos) break;
        list.remove_prefix(comma + 1);
    }
    return {};
}

std::string format_function_set(const FunctionSet& set) {
    std::string out;
    for (unsigned fc = 1; fc < set.size(); ++fc) {
        if (!set.test(fc)) continue;
        unsigned last = fc;
        while (last + 1 < set.size() && set.test(last + 1)) ++last;
        if (!out.empty()) out += ',';
        out += std::to_string(fc);
        if (last > fc) out += '-' + std::to_string(last);
        fc = last;
    }
    return out;
}

}  // namespace mbstorm::codec
