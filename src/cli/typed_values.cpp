#include "cli/typed_values.hpp"

#include <fmt/format.h>

#include <array>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <utility>

namespace mbstorm::cli {
namespace {

struct TypeName {
    ValueType type;
    std::string_view name;
};
constexpr std::array<TypeName, 10> kTypes = {{{ValueType::U16, "u16"},
                                              {ValueType::I16, "i16"},
                                              {ValueType::U32, "u32"},
                                              {ValueType::I32, "i32"},
                                              {ValueType::U64, "u64"},
                                              {ValueType::I64, "i64"},
                                              {ValueType::F32, "f32"},
                                              {ValueType::F64, "f64"},
                                              {ValueType::String, "string"},
                                              {ValueType::Bits, "bits"}}};

// A register's two bytes in the order the word order puts them (BADC and DCBA swap them).
bool swaps_bytes(codec::WordOrder order) {
    return order == codec::WordOrder::BADC || order == codec::WordOrder::DCBA;
}

bool parse_signed(const std::string& text, long long lo, long long hi, long long& out) {
    errno = 0;
    char* end = nullptr;
    long long v = std::strtoll(text.c_str(), &end, 0);
    if (text.empty() || *end != '\0' || errno != 0 || v < lo || v > hi) return false;
    out = v;
    return true;
}

bool parse_unsigned(const std::string& text, unsigned long long hi, unsigned long long& out) {
    errno = 0;
    char* end = nullptr;
    if (text.empty() || text.front() == '-') return false;
    unsigned long long v = std::strtoull(text.c_str(), &end, 0);
    if (*end != '\0' || errno != 0 || v > hi) return false;
    out = v;
    return true;
}

bool parse_double(const std::string& text, double& out) {
    errno = 0;
    char* end = nullptr;
    double v = std::strtod(text.c_str(), &end);
    if (text.empty() || *end != '\0' || errno == ERANGE) return false;
    out = v;
    return true;
}

std::string number_text(double v) {
    return fmt::format("{}", v);
}

}  // namespace

bool value_type_from_name(std::string_view name, ValueType& out) noexcept {
    for (const auto& t : kTypes) {
        if (t.name == name) {
            out = t.type;
            return true;
        }
    }
    return false;
}

std::string_view value_type_name(ValueType type) noexcept {
    for (const auto& t : kTypes) {
        if (t.type == type) return t.name;
    }
    return "?";
}

std::size_t registers_per_value(ValueType type) noexcept {
    switch (type) {
        case ValueType::U32:
        case ValueType::I32:
        case ValueType::F32:
            return 2;
        case ValueType::U64:
        case ValueType::I64:
        case ValueType::F64:
            return 4;
        default:
            return 1;
    }
}

bool parse_bit(std::string_view text, bool& out) noexcept {
    if (text == "1" || text == "on" || text == "ON" || text == "true") {
        out = true;
        return true;
    }
    if (text == "0" || text == "off" || text == "OFF" || text == "false") {
        out = false;
        return true;
    }
    return false;
}

std::vector<TypedValue> values_from_registers(std::span<const std::uint16_t> regs,
                                              std::uint16_t first_address, ValueType type,
                                              codec::WordOrder order) {
    std::vector<TypedValue> out;
    if (type == ValueType::String) {
        std::string text;
        for (std::uint16_t r : regs) {
            char hi = static_cast<char>(r >> 8), lo = static_cast<char>(r & 0xFF);
            if (swaps_bytes(order)) std::swap(hi, lo);
            text += hi;
            text += lo;
        }
        // Devices pad strings with NULs (or spaces); the value ends at the first NUL.
        if (auto nul = text.find('\0'); nul != std::string::npos) text.resize(nul);
        out.push_back({first_address, text, 0, false});
        return out;
    }
    const std::size_t width = registers_per_value(type);
    for (std::size_t i = 0; i + width <= regs.size(); i += width) {
        const auto address = static_cast<std::uint16_t>(first_address + i);
        const std::uint16_t r0 = regs[i];
        TypedValue v{address, {}, 0, true};
        switch (type) {
            case ValueType::U16:
                v.number =
                    swaps_bytes(order) ? static_cast<std::uint16_t>((r0 >> 8) | (r0 << 8)) : r0;
                break;
            case ValueType::I16: {
                std::uint16_t w =
                    swaps_bytes(order) ? static_cast<std::uint16_t>((r0 >> 8) | (r0 << 8)) : r0;
                v.number = static_cast<std::int16_t>(w);
                break;
            }
            case ValueType::U32:
                v.number = codec::u32_from_registers(regs.subspan(i).first<2>(), order);
                break;
            case ValueType::I32:
                v.number = codec::i32_from_registers(regs.subspan(i).first<2>(), order);
                break;
            case ValueType::F32: {
                // The shortest text that round-trips the float itself (0.1, not the widened
                // 0.10000000149011612); the JSON number is that text read back as a double.
                const float f = codec::f32_from_registers(regs.subspan(i).first<2>(), order);
                v.text = fmt::format("{}", f);
                v.number = std::strtod(v.text.c_str(), nullptr);
                break;
            }
            case ValueType::U64: {
                auto n = codec::u64_from_registers(regs.subspan(i).first<4>(), order);
                v.number = static_cast<double>(n);
                v.text = fmt::format("{}", n);
                break;
            }
            case ValueType::I64: {
                auto n = codec::i64_from_registers(regs.subspan(i).first<4>(), order);
                v.number = static_cast<double>(n);
                v.text = fmt::format("{}", n);
                break;
            }
            case ValueType::F64:
                v.number = codec::f64_from_registers(regs.subspan(i).first<4>(), order);
                break;
            case ValueType::Bits:
                v.text = fmt::format("{:016b}", r0);
                v.is_number = false;
                break;
            case ValueType::String:
                break;
        }
        if (v.text.empty()) v.text = number_text(v.number);
        out.push_back(std::move(v));
    }
    return out;
}

namespace {

// registers_from_text's work: "" or what is wrong with which value.
std::string registers_problem(const std::vector<std::string>& texts, ValueType type,
                              codec::WordOrder order, std::vector<std::uint16_t>& out) {
    auto swap = [&](std::uint16_t w) {
        return swaps_bytes(order) ? static_cast<std::uint16_t>((w >> 8) | (w << 8)) : w;
    };
    auto push = [&](std::span<const std::uint16_t> regs) {
        out.insert(out.end(), regs.begin(), regs.end());
    };
    if (type == ValueType::String) {
        std::string text;
        for (const auto& t : texts) text += (text.empty() ? "" : " ") + t;
        if (text.size() % 2) text += '\0';
        for (std::size_t i = 0; i < text.size(); i += 2) {
            auto w = static_cast<std::uint16_t>((static_cast<unsigned char>(text[i]) << 8) |
                                                static_cast<unsigned char>(text[i + 1]));
            out.push_back(swap(w));
        }
        return {};
    }
    for (const auto& t : texts) {
        long long s = 0;
        unsigned long long u = 0;
        double d = 0;
        auto bad = [&](const std::string& range) {
            return fmt::format("value '{}': valid {} for {}", t, range, value_type_name(type));
        };
        switch (type) {
            case ValueType::U16:
                if (!parse_unsigned(t, 0xFFFF, u)) return bad("0..65535");
                out.push_back(swap(static_cast<std::uint16_t>(u)));
                break;
            case ValueType::I16:
                if (!parse_signed(t, -32768, 32767, s)) return bad("-32768..32767");
                out.push_back(swap(static_cast<std::uint16_t>(static_cast<std::int16_t>(s))));
                break;
            case ValueType::Bits:
                if (!parse_unsigned(t, 0xFFFF, u)) return bad("0..0xFFFF (0b... not accepted)");
                out.push_back(static_cast<std::uint16_t>(u));
                break;
            case ValueType::U32:
                if (!parse_unsigned(t, 0xFFFFFFFFull, u)) return bad("0..4294967295");
                push(codec::registers_from_u32(static_cast<std::uint32_t>(u), order));
                break;
            case ValueType::I32:
                if (!parse_signed(t, std::numeric_limits<std::int32_t>::min(),
                                  std::numeric_limits<std::int32_t>::max(), s))
                    return bad("-2147483648..2147483647");
                push(codec::registers_from_i32(static_cast<std::int32_t>(s), order));
                break;
            case ValueType::U64:
                if (!parse_unsigned(t, std::numeric_limits<std::uint64_t>::max(), u))
                    return bad("0..18446744073709551615");
                push(codec::registers_from_u64(u, order));
                break;
            case ValueType::I64:
                if (!parse_signed(t, std::numeric_limits<long long>::min(),
                                  std::numeric_limits<long long>::max(), s))
                    return bad("a 64-bit signed integer");
                push(codec::registers_from_i64(s, order));
                break;
            case ValueType::F32:
                if (!parse_double(t, d) || (std::isfinite(d) && std::fabs(d) > 3.4028235e38))
                    return bad("a number within float range");
                push(codec::registers_from_f32(static_cast<float>(d), order));
                break;
            case ValueType::F64:
                if (!parse_double(t, d)) return bad("a number");
                push(codec::registers_from_f64(d, order));
                break;
            case ValueType::String:
                break;
        }
    }
    return {};
}

}  // namespace

Error registers_from_text(const std::vector<std::string>& texts, ValueType type,
                          codec::WordOrder order, std::vector<std::uint16_t>& out) {
    std::string why = registers_problem(texts, type, order, out);
    if (why.empty()) return {};
    return Error(ErrorCode::InvalidInput, std::move(why));
}

}  // namespace mbstorm::cli
