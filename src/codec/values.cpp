// Value helpers: bit packing, word orders, reference numbers, hex text.
#include "codec/values.hpp"

#include <bit>
#include <iterator>
#include <utility>

#include "codec/hex.hpp"

namespace mbstorm::codec {

// ---- Bits

namespace {
template <typename Bit>
EncodeResult pack(std::span<const Bit> bits, MutableBytes out) noexcept {
    const std::size_t n = packed_bit_bytes(bits.size());
    if (out.size() < n) return {0, CodecError::BufferTooSmall};
    for (std::size_t i = 0; i < n; ++i) out[i] = 0;
    for (std::size_t i = 0; i < bits.size(); ++i) {
        if (bits[i]) out[i / 8] = static_cast<std::uint8_t>(out[i / 8] | (1u << (i % 8)));
    }
    return {n, CodecError::Ok};
}
}  // namespace

EncodeResult pack_bits(std::span<const bool> bits, MutableBytes out) noexcept {
    return pack(bits, out);
}

EncodeResult pack_bit_bytes(std::span<const std::uint8_t> bits, MutableBytes out) noexcept {
    return pack(bits, out);
}

bool unpack_bits(Bytes packed, std::span<bool> out) noexcept {
    if (packed.size() < packed_bit_bytes(out.size())) return false;
    for (std::size_t i = 0; i < out.size(); ++i) out[i] = bit_at(packed, i);
    return true;
}

bool padding_is_zero(Bytes packed, std::size_t bit_count) noexcept {
    for (std::size_t i = bit_count; i < packed.size() * 8; ++i) {
        if (bit_at(packed, i)) return false;
    }
    return true;
}

// ---- Word orders

namespace {

constexpr bool swaps_words(WordOrder o) noexcept {
    return o == WordOrder::CDAB || o == WordOrder::DCBA;
}
constexpr bool swaps_bytes(WordOrder o) noexcept {
    return o == WordOrder::BADC || o == WordOrder::DCBA;
}
constexpr std::uint16_t swap16(std::uint16_t v) noexcept {
    return static_cast<std::uint16_t>((v >> 8) | (v << 8));
}

// Splits `value` into N big-endian words, then applies the order.
template <std::size_t N, typename U>
std::array<std::uint16_t, N> to_words(U value, WordOrder order) noexcept {
    std::array<std::uint16_t, N> w{};
    for (std::size_t i = 0; i < N; ++i) {
        w[i] = static_cast<std::uint16_t>(value >> (16 * (N - 1 - i)));
    }
    if (swaps_bytes(order)) {
        for (auto& x : w) x = swap16(x);
    }
    if (swaps_words(order)) {
        for (std::size_t i = 0; i < N / 2; ++i) std::swap(w[i], w[N - 1 - i]);
    }
    return w;
}

template <typename U, std::size_t N>
U from_words(std::span<const std::uint16_t, N> regs, WordOrder order) noexcept {
    U value = 0;
    for (std::size_t i = 0; i < N; ++i) {
        std::uint16_t w = swaps_words(order) ? regs[N - 1 - i] : regs[i];
        if (swaps_bytes(order)) w = swap16(w);
        value = static_cast<U>((value << 16) | w);
    }
    return value;
}

constexpr std::string_view kWordOrderNames[] = {"ABCD", "CDAB", "BADC", "DCBA"};

bool equals_ignoring_case(std::string_view a, std::string_view b) noexcept {
    if (a.size() != b.size()) return false;
    for (std::size_t i = 0; i < a.size(); ++i) {
        char x = a[i];
        char y = b[i];
        if (x >= 'A' && x <= 'Z') x = static_cast<char>(x - 'A' + 'a');
        if (y >= 'A' && y <= 'Z') y = static_cast<char>(y - 'A' + 'a');
        if (x != y) return false;
    }
    return true;
}

}  // namespace

std::string_view word_order_name(WordOrder order) noexcept {
    const auto i = static_cast<std::size_t>(order);
    return i < std::size(kWordOrderNames) ? kWordOrderNames[i] : std::string_view("?");
}

bool word_order_from_name(std::string_view name, WordOrder& out) noexcept {
    for (std::size_t i = 0; i < std::size(kWordOrderNames); ++i) {
        if (equals_ignoring_case(name, kWordOrderNames[i])) {
            out = static_cast<WordOrder>(i);
            return true;
        }
    }
    return false;
}

Registers2 registers_from_u32(std::uint32_t value, WordOrder order) noexcept {
    return to_words<2>(value, order);
}
Registers2 registers_from_i32(std::int32_t value, WordOrder order) noexcept {
    return to_words<2>(static_cast<std::uint32_t>(value), order);
}
Registers2 registers_from_f32(float value, WordOrder order) noexcept {
    return to_words<2>(std::bit_cast<std::uint32_t>(value), order);
}
Registers4 registers_from_u64(std::uint64_t value, WordOrder order) noexcept {
    return to_words<4>(value, order);
}
Registers4 registers_from_i64(std::int64_t value, WordOrder order) noexcept {
    return to_words<4>(static_cast<std::uint64_t>(value), order);
}
Registers4 registers_from_f64(double value, WordOrder order) noexcept {
    return to_words<4>(std::bit_cast<std::uint64_t>(value), order);
}

std::uint32_t u32_from_registers(std::span<const std::uint16_t, 2> regs, WordOrder order) noexcept {
    return from_words<std::uint32_t>(regs, order);
}
std::int32_t i32_from_registers(std::span<const std::uint16_t, 2> regs, WordOrder order) noexcept {
    return static_cast<std::int32_t>(from_words<std::uint32_t>(regs, order));
}
float f32_from_registers(std::span<const std::uint16_t, 2> regs, WordOrder order) noexcept {
    return std::bit_cast<float>(from_words<std::uint32_t>(regs, order));
}
std::uint64_t u64_from_registers(std::span<const std::uint16_t, 4> regs, WordOrder order) noexcept {
    return from_words<std::uint64_t>(regs, order);
}
std::int64_t i64_from_registers(std::span<const std::uint16_t, 4> regs, WordOrder order) noexcept {
    return static_cast<std::int64_t>(from_words<std::uint64_t>(regs, order));
}
double f64_from_registers(std::span<const std::uint16_t, 4> regs, WordOrder order) noexcept {
    return std::bit_cast<double>(from_words<std::uint64_t>(regs, order));
}

// ---- Tables and reference numbers

namespace {
constexpr std::string_view kTableNames[] = {"coils", "discrete_inputs", "input_registers",
                                            "holding_registers"};
// Leading digit of each table's reference numbers, in Table order.
constexpr char kTableDigits[] = {'0', '1', '3', '4'};
}  // namespace

std::string_view table_name(Table table) noexcept {
    const auto i = static_cast<std::size_t>(table);
    return i < std::size(kTableNames) ? kTableNames[i] : std::string_view("?");
}

bool table_from_name(std::string_view name, Table& out) noexcept {
    for (std::size_t i = 0; i < std::size(kTableNames); ++i) {
        if (equals_ignoring_case(name, kTableNames[i])) {
            out = static_cast<Table>(i);
            return true;
        }
    }
    return false;
}

bool parse_reference(std::string_view text, Reference& out) noexcept {
    if (text.size() != 5 && text.size() != 6) return false;
    std::uint32_t number = 0;
    for (std::size_t i = 1; i < text.size(); ++i) {
        const char c = text[i];
        if (c < '0' || c > '9') return false;
        number = number * 10 + static_cast<std::uint32_t>(c - '0');
    }
    const std::uint32_t max = text.size() == 5 ? 9999 : 65536;
    if (number < 1 || number > max) return false;
    for (std::size_t t = 0; t < std::size(kTableDigits); ++t) {
        if (text[0] == kTableDigits[t]) {
            out.table = static_cast<Table>(t);
            out.offset = static_cast<std::uint16_t>(number - 1);
            return true;
        }
    }
    return false;
}

std::string format_reference(Reference ref, bool six_digits) {
    const auto t = static_cast<std::size_t>(ref.table);
    const char lead = t < std::size(kTableDigits) ? kTableDigits[t] : '?';
    const std::uint32_t number = ref.offset + 1u;
    const int width = (six_digits || ref.offset >= 9999) ? 5 : 4;
    std::string s(1 + static_cast<std::size_t>(width), '0');
    s[0] = lead;
    std::uint32_t n = number;
    for (int i = width; i >= 1; --i) {
        s[static_cast<std::size_t>(i)] = static_cast<char>('0' + n % 10);
        n /= 10;
    }
    return s;
}

// ---- Hex text

namespace {
constexpr bool is_separator(char c) noexcept {
    return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == ':' || c == '-' || c == ',';
}
}  // namespace

HexParseResult parse_hex(std::string_view text, MutableBytes out) noexcept {
    HexParseResult r;
    std::size_t i = 0;
    while (i < text.size()) {
        if (is_separator(text[i])) {
            ++i;
            continue;
        }
        // One group: optional 0x prefix, then digit pairs up to the next separator.
        const std::size_t group_start = i;
        if (i + 1 < text.size() && text[i] == '0' && (text[i + 1] == 'x' || text[i + 1] == 'X')) {
            i += 2;
        }
        const std::size_t digits_start = i;
        while (i < text.size() && !is_separator(text[i])) {
            if (hex::digit_value(static_cast<std::uint8_t>(text[i])) == hex::kNotHex) {
                r.error = CodecError::BadHexDigit;
                r.position = i;
                return r;
            }
            ++i;
        }
        const std::size_t digits = i - digits_start;
        if (digits == 0 || digits % 2 != 0) {
            r.error = digits == 0 ? CodecError::BadHexDigit : CodecError::OddHexLength;
            r.position = group_start;
            return r;
        }
        for (std::size_t d = digits_start; d < i; d += 2) {
            if (r.size >= out.size()) {
                r.error = CodecError::BufferTooSmall;
                r.position = d;
                return r;
            }
            out[r.size++] = static_cast<std::uint8_t>(
                (hex::digit_value(static_cast<std::uint8_t>(text[d])) << 4) |
                hex::digit_value(static_cast<std::uint8_t>(text[d + 1])));
        }
    }
    if (r.size == 0) r.error = CodecError::Empty;
    return r;
}

std::string format_hex(Bytes bytes, char separator) {
    std::string s;
    s.reserve(bytes.size() * 3);
    for (std::size_t i = 0; i < bytes.size(); ++i) {
        if (i > 0 && separator != '\0') s.push_back(separator);
        s.push_back(hex::kUpperDigits[bytes[i] >> 4]);
        s.push_back(hex::kUpperDigits[bytes[i] & 0x0F]);
    }
    return s;
}

}  // namespace mbstorm::codec
