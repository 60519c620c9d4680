// libFuzzer harness: the values a user types on the command line. The first byte picks the
// parser (durations, addresses and ranges of each table, typed register values in each word
// order, bits, value type names); the rest is the text.
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "cli/typed_values.hpp"
#include "codec/address.hpp"
#include "stats/duration_text.hpp"

namespace {

using namespace mbstorm;

void typed(std::string_view text, std::uint8_t pick) {
    cli::ValueType type = cli::ValueType::U16;
    const auto all = {cli::ValueType::U16, cli::ValueType::I16, cli::ValueType::U32,
                      cli::ValueType::I32, cli::ValueType::U64, cli::ValueType::I64,
                      cli::ValueType::F32, cli::ValueType::F64, cli::ValueType::String,
                      cli::ValueType::Bits};
    type = *(all.begin() + pick % all.size());
    const auto order = static_cast<codec::WordOrder>((pick / 16) % 4);
    std::vector<std::string> texts;
    for (std::size_t at = 0; at <= text.size();) {
        const std::size_t comma = std::min(text.find(',', at), text.size());
        texts.emplace_back(text.substr(at, comma - at));
        at = comma + 1;
    }
    std::vector<std::uint16_t> regs;
    if (cli::registers_from_text(texts, type, order, regs).empty() && !regs.empty())
        (void)cli::values_from_registers(regs, 0, type, order);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size == 0) return 0;
    const std::uint8_t pick = data[0];
    const std::string_view text(reinterpret_cast<const char*>(data + 1), size - 1);
    switch (pick % 5) {
        case 0: {
            std::uint64_t ns = 0;
            (void)stats::parse_duration_ns(text, ns);
            break;
        }
        case 1: {
            codec::AddressRange range;
            std::optional<codec::Table> table;
            if (pick / 5 % 5 < 4) table = static_cast<codec::Table>(pick / 5 % 5);
            (void)codec::parse_address_range(text, table, range);
            break;
        }
        case 2:
            typed(text, pick / 5);
            break;
        case 3: {
            bool bit = false;
            (void)cli::parse_bit(text, bit);
            break;
        }
        case 4: {
            cli::ValueType type;
            (void)cli::value_type_from_name(text, type);
            break;
        }
    }
    return 0;
}
