// libFuzzer harness: the values a user types on the command line. The first byte picks the
// parser (durations, addresses and ranges of each table, typed register values in each word
// order, bits, value type names); the rest is the text. Invariants: a duration with a unit
// does not depend on the default unit, a bare one means the same with "s" written; an address
// range is ordered, and a protocol-address one reads back from format_protocol_address; typed
// values written and read back print the same (and integers give the same registers, bits
// the register's binary digits); accepted bits and type names read back from their canonical
// spelling.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "cli/typed_values.hpp"
#include "codec/address.hpp"
#include "stats/duration_text.hpp"

namespace {

using namespace mbstorm;

void check(bool ok) {
    if (!ok) std::abort();
}

void duration(std::string_view text) {
    std::uint64_t ns = 0, again = 0;
    if (!stats::parse_duration_ns(text, ns)) return;
    std::string_view t = text;
    while (!t.empty() && t.front() == ' ') t.remove_prefix(1);
    while (!t.empty() && t.back() == ' ') t.remove_suffix(1);
    const bool bare = t.find_first_not_of("0123456789.") == std::string_view::npos;
    if (bare)
        check(stats::parse_duration_ns(std::string(t) + "s", again, 1) && again == ns);
    else
        check(stats::parse_duration_ns(text, again, 1) && again == ns);
}

void address(std::string_view text, std::optional<codec::Table> table) {
    codec::AddressRange range;
    if (!codec::parse_address_range(text, table, range).empty()) return;
    check(range.first <= range.last && (range.is_range || range.first == range.last));
    check(!range.reference || table.has_value());
    if (range.reference) return;
    std::string written = codec::format_protocol_address(range.first);
    if (range.is_range) written += "-" + codec::format_protocol_address(range.last);
    codec::AddressRange again;
    check(codec::parse_address_range(written, table, again).empty());
    check(again.first == range.first && again.last == range.last &&
          again.is_range == range.is_range && !again.reference);
}

std::vector<std::string> texts_of(const std::vector<cli::TypedValue>& values) {
    std::vector<std::string> texts;
    for (const auto& v : values) texts.push_back(v.text);
    return texts;
}

void typed(std::string_view text, std::uint8_t pick) {
    const auto all = {cli::ValueType::U16, cli::ValueType::I16, cli::ValueType::U32,
                      cli::ValueType::I32, cli::ValueType::U64, cli::ValueType::I64,
                      cli::ValueType::F32, cli::ValueType::F64, cli::ValueType::String,
                      cli::ValueType::Bits};
    const cli::ValueType type = *(all.begin() + pick % all.size());
    const auto order = static_cast<codec::WordOrder>((pick / 16) % 4);
    std::vector<std::string> texts;
    for (std::size_t at = 0; at <= text.size();) {
        const std::size_t comma = std::min(text.find(',', at), text.size());
        texts.emplace_back(text.substr(at, comma - at));
        at = comma + 1;
    }
    std::vector<std::uint16_t> regs;
    if (!cli::registers_from_text(texts, type, order, regs).ok() || regs.empty()) return;
    const auto values = cli::values_from_registers(regs, 0, type, order);
    if (type == cli::ValueType::Bits) {  // printed as binary digits, which write does not take
        check(values.size() == regs.size());
        for (std::size_t i = 0; i < regs.size(); ++i)
            check(std::strtoul(values[i].text.c_str(), nullptr, 2) == regs[i]);
        return;
    }
    std::vector<std::uint16_t> again;
    check(cli::registers_from_text(texts_of(values), type, order, again).ok());
    check(texts_of(cli::values_from_registers(again, 0, type, order)) == texts_of(values));
    // Integers are exact; a float's NaN payload and a string's NULs may not come back.
    if (type < cli::ValueType::F32) check(again == regs);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size == 0) return 0;
    const std::uint8_t pick = data[0];
    const std::string_view text(reinterpret_cast<const char*>(data + 1), size - 1);
    switch (pick % 5) {
        case 0:
            duration(text);
            break;
        case 1: {
            std::optional<codec::Table> table;
            if (pick / 5 % 5 < 4) table = static_cast<codec::Table>(pick / 5 % 5);
            address(text, table);
            break;
        }
        case 2:
            typed(text, pick / 5);
            break;
        case 3: {
            bool bit = false, again = !bit;
            if (cli::parse_bit(text, bit))
                check(cli::parse_bit(bit ? "1" : "0", again) && again == bit);
            break;
        }
        case 4: {
            cli::ValueType type;
            if (cli::value_type_from_name(text, type)) check(cli::value_type_name(type) == text);
            break;
        }
    }
    return 0;
}
