// Value helpers: bit packing, word orders, reference numbers, hex text.
#include <gtest/gtest.h>

#include <array>
#include <bit>
#include <cmath>
#include <limits>
#include <random>
#include <string>

#include "codec/values.hpp"
#include "framing_test_support.hpp"

namespace mbstorm::codec {
namespace {

using framing_test::ByteVec;
using framing_test::hex_bytes;

constexpr WordOrder kOrders[] = {WordOrder::ABCD, WordOrder::CDAB, WordOrder::BADC,
                                 WordOrder::DCBA};

// ---- Bits

TEST(Bits, PacksLsbFirstWithZeroPadding) {
    const std::array<bool, 10> bits = {true, false, true, true, false, false, true, true,  // CD
                                       true, false};                                       // 01
    std::array<std::uint8_t, 4> out;
    out.fill(0xEE);
    const EncodeResult r = pack_bits(bits, out);
    ASSERT_TRUE(r.ok());
    ASSERT_EQ(r.size, 2u);
    EXPECT_EQ(out[0], 0xCD);
    EXPECT_EQ(out[1], 0x01);
    EXPECT_EQ(out[2], 0xEE);  // untouched past the packed size
    EXPECT_TRUE(padding_is_zero(Bytes(out.data(), 2), 10));
}

TEST(Bits, PackFromBytesTreatsNonZeroAsOn) {
    const std::array<std::uint8_t, 9> bits = {1, 0, 2, 0xFF, 0, 0, 0, 0, 7};
    std::array<std::uint8_t, 2> out{};
    const EncodeResult r = pack_bit_bytes(bits, out);
    ASSERT_TRUE(r.ok());
    EXPECT_EQ(r.size, 2u);
    EXPECT_EQ(out[0], 0x0D);
    EXPECT_EQ(out[1], 0x01);
}

TEST(Bits, SizesAndErrors) {
    EXPECT_EQ(packed_bit_bytes(0), 0u);
    EXPECT_EQ(packed_bit_bytes(1), 1u);
    EXPECT_EQ(packed_bit_bytes(8), 1u);
    EXPECT_EQ(packed_bit_bytes(9), 2u);
    EXPECT_EQ(packed_bit_bytes(2000), 250u);
    std::array<bool, 9> bits{};
    std::array<std::uint8_t, 1> small{};
    EXPECT_EQ(pack_bits(bits, small).error, CodecError::BufferTooSmall);
    EXPECT_EQ(pack_bits({}, small).size, 0u);
    std::array<bool, 9> out{};
    EXPECT_FALSE(unpack_bits(Bytes(small.data(), 1), out));
}

TEST(Bits, UnpackAndPaddingCheck) {
    const ByteVec packed = {0xCD, 0x01};
    std::array<bool, 10> bits{};
    ASSERT_TRUE(unpack_bits(packed, bits));
    const std::array<bool, 10> want = {true,  false, true, true, false,
                                       false, true,  true, true, false};
    EXPECT_EQ(bits, want);
    EXPECT_TRUE(bit_at(packed, 8));
    EXPECT_FALSE(bit_at(packed, 9));
    EXPECT_TRUE(padding_is_zero(packed, 10));
    EXPECT_TRUE(padding_is_zero(packed, 9));
    EXPECT_FALSE(padding_is_zero(packed, 8));  // bit 8 is set but lies in the padding
    EXPECT_TRUE(padding_is_zero({}, 0));
}

TEST(Bits, RoundTripsEveryCount) {
    std::mt19937 rng(7);
    for (std::size_t n = 0; n <= 2000; n += (n < 20 ? 1 : 37)) {
        std::vector<char> raw(n);
        for (auto& b : raw) b = static_cast<char>(rng() & 1);
        std::unique_ptr<bool[]> bits(new bool[n + 1]);
        for (std::size_t i = 0; i < n; ++i) bits[i] = raw[i] != 0;
        std::array<std::uint8_t, 250> packed{};
        const EncodeResult r = pack_bits(std::span<const bool>(bits.get(), n), packed);
        ASSERT_TRUE(r.ok());
        ASSERT_EQ(r.size, packed_bit_bytes(n));
        EXPECT_TRUE(padding_is_zero(Bytes(packed.data(), r.size), n));
        std::unique_ptr<bool[]> back(new bool[n + 1]);
        ASSERT_TRUE(unpack_bits(Bytes(packed.data(), r.size), std::span<bool>(back.get(), n)));
        for (std::size_t i = 0; i < n; ++i) ASSERT_EQ(back[i], bits[i]) << n << " " << i;
    }
}

// ---- Word orders

TEST(WordOrder, ThirtyTwoBitLayouts) {
    const std::uint32_t v = 0x11223344;
    EXPECT_EQ(registers_from_u32(v, WordOrder::ABCD), (Registers2{0x1122, 0x3344}));
    EXPECT_EQ(registers_from_u32(v, WordOrder::CDAB), (Registers2{0x3344, 0x1122}));
    EXPECT_EQ(registers_from_u32(v, WordOrder::BADC), (Registers2{0x2211, 0x4433}));
    EXPECT_EQ(registers_from_u32(v, WordOrder::DCBA), (Registers2{0x4433, 0x2211}));
}

TEST(WordOrder, SixtyFourBitLayouts) {
    const std::uint64_t v = 0x1122334455667788;
    EXPECT_EQ(registers_from_u64(v, WordOrder::ABCD), (Registers4{0x1122, 0x3344, 0x5566, 0x7788}));
    EXPECT_EQ(registers_from_u64(v, WordOrder::CDAB), (Registers4{0x7788, 0x5566, 0x3344, 0x1122}));
    EXPECT_EQ(registers_from_u64(v, WordOrder::BADC), (Registers4{0x2211, 0x4433, 0x6655, 0x8877}));
    EXPECT_EQ(registers_from_u64(v, WordOrder::DCBA), (Registers4{0x8877, 0x6655, 0x4433, 0x2211}));
}

TEST(WordOrder, KnownFloats) {
    // 123.456f = 0x42F6E979.
    EXPECT_EQ(registers_from_f32(123.456f, WordOrder::ABCD), (Registers2{0x42F6, 0xE979}));
    EXPECT_EQ(registers_from_f32(123.456f, WordOrder::CDAB), (Registers2{0xE979, 0x42F6}));
    EXPECT_EQ(registers_from_f32(123.456f, WordOrder::BADC), (Registers2{0xF642, 0x79E9}));
    EXPECT_EQ(registers_from_f32(123.456f, WordOrder::DCBA), (Registers2{0x79E9, 0xF642}));
    EXPECT_EQ(f32_from_registers(Registers2{0x42F6, 0xE979}, WordOrder::ABCD), 123.456f);
    EXPECT_EQ(f32_from_registers(Registers2{0x3F80, 0x0000}, WordOrder::ABCD), 1.0f);
    EXPECT_EQ(f32_from_registers(Registers2{0x0000, 0xC120}, WordOrder::CDAB), -10.0f);
    // 1.0 = 0x3FF0000000000000; pi = 0x400921FB54442D18.
    EXPECT_EQ(registers_from_f64(1.0, WordOrder::ABCD), (Registers4{0x3FF0, 0, 0, 0}));
    EXPECT_EQ(registers_from_f64(M_PI, WordOrder::ABCD),
              (Registers4{0x4009, 0x21FB, 0x5444, 0x2D18}));
    EXPECT_EQ(registers_from_f64(M_PI, WordOrder::DCBA),
              (Registers4{0x182D, 0x4454, 0xFB21, 0x0940}));
    EXPECT_EQ(f64_from_registers(Registers4{0x2D18, 0x5444, 0x21FB, 0x4009}, WordOrder::CDAB),
              M_PI);
}

TEST(WordOrder, KnownIntegers) {
    EXPECT_EQ(registers_from_i32(-2, WordOrder::ABCD), (Registers2{0xFFFF, 0xFFFE}));
    EXPECT_EQ(registers_from_i32(-2, WordOrder::CDAB), (Registers2{0xFFFE, 0xFFFF}));
    EXPECT_EQ(i32_from_registers(Registers2{0x8000, 0x0000}, WordOrder::ABCD),
              std::numeric_limits<std::int32_t>::min());
    EXPECT_EQ(registers_from_i64(-1, WordOrder::BADC),
              (Registers4{0xFFFF, 0xFFFF, 0xFFFF, 0xFFFF}));
    EXPECT_EQ(i64_from_registers(Registers4{0xFEFF, 0xFFFF, 0xFFFF, 0xFFFF}, WordOrder::DCBA), -2);
    EXPECT_EQ(u32_from_registers(Registers2{0x0001, 0x0000}, WordOrder::CDAB), 1u);
}

TEST(WordOrder, EveryOrderRoundTrips) {
    std::mt19937_64 rng(99);
    for (int i = 0; i < 2000; ++i) {
        const std::uint64_t bits = rng();
        for (WordOrder o : kOrders) {
            const auto u32 = static_cast<std::uint32_t>(bits);
            ASSERT_EQ(u32_from_registers(registers_from_u32(u32, o), o), u32);
            const auto i32 = static_cast<std::int32_t>(u32);
            ASSERT_EQ(i32_from_registers(registers_from_i32(i32, o), o), i32);
            const float f = std::bit_cast<float>(u32);
            ASSERT_EQ(std::bit_cast<std::uint32_t>(f32_from_registers(registers_from_f32(f, o), o)),
                      u32);  // bit-exact, NaNs included
            ASSERT_EQ(u64_from_registers(registers_from_u64(bits, o), o), bits);
            const auto i64 = static_cast<std::int64_t>(bits);
            ASSERT_EQ(i64_from_registers(registers_from_i64(i64, o), o), i64);
            const double d = std::bit_cast<double>(bits);
            ASSERT_EQ(std::bit_cast<std::uint64_t>(f64_from_registers(registers_from_f64(d, o), o)),
                      bits);
        }
    }
    for (float f : {0.0f, -0.0f, std::numeric_limits<float>::infinity(),
                    std::numeric_limits<float>::denorm_min(), -1e38f}) {
        for (WordOrder o : kOrders) {
            EXPECT_EQ(std::bit_cast<std::uint32_t>(f32_from_registers(registers_from_f32(f, o), o)),
                      std::bit_cast<std::uint32_t>(f));
        }
    }
}

TEST(WordOrder, DifferentOrdersGiveDifferentRegistersForAsymmetricValues) {
    const auto abcd = registers_from_u32(0x11223344, WordOrder::ABCD);
    for (WordOrder o : kOrders) {
        if (o == WordOrder::ABCD) continue;
        EXPECT_NE(registers_from_u32(0x11223344, o), abcd);
        EXPECT_NE(u32_from_registers(abcd, o), 0x11223344u);
    }
}

TEST(WordOrder, Names) {
    for (WordOrder o : kOrders) {
        WordOrder back = WordOrder::ABCD;
        ASSERT_TRUE(word_order_from_name(word_order_name(o), back));
        EXPECT_EQ(back, o);
    }
    WordOrder o{};
    EXPECT_TRUE(word_order_from_name("cdab", o));
    EXPECT_EQ(o, WordOrder::CDAB);
    EXPECT_EQ(word_order_name(WordOrder::BADC), "BADC");
    EXPECT_FALSE(word_order_from_name("ABDC", o));
    EXPECT_FALSE(word_order_from_name("", o));
}

// ---- Tables and references

TEST(Table, Names) {
    EXPECT_EQ(table_name(Table::Coils), "coils");
    EXPECT_EQ(table_name(Table::DiscreteInputs), "discrete_inputs");
    EXPECT_EQ(table_name(Table::InputRegisters), "input_registers");
    EXPECT_EQ(table_name(Table::HoldingRegisters), "holding_registers");
    for (Table t :
         {Table::Coils, Table::DiscreteInputs, Table::InputRegisters, Table::HoldingRegisters}) {
        Table back = Table::Coils;
        ASSERT_TRUE(table_from_name(table_name(t), back));
        EXPECT_EQ(back, t);
    }
    Table t{};
    EXPECT_FALSE(table_from_name("registers", t));
    EXPECT_TRUE(is_bit_table(Table::Coils));
    EXPECT_TRUE(is_bit_table(Table::DiscreteInputs));
    EXPECT_FALSE(is_bit_table(Table::HoldingRegisters));
}

Reference ref(std::string_view s) {
    Reference r{Table::Coils, 0xBEEF};
    EXPECT_TRUE(parse_reference(s, r)) << s;
    return r;
}

TEST(Reference, ParsesEveryTable) {
    EXPECT_EQ(ref("00001"), (Reference{Table::Coils, 0}));
    EXPECT_EQ(ref("09999"), (Reference{Table::Coils, 9998}));
    EXPECT_EQ(ref("10001"), (Reference{Table::DiscreteInputs, 0}));
    EXPECT_EQ(ref("30001"), (Reference{Table::InputRegisters, 0}));
    EXPECT_EQ(ref("40001"), (Reference{Table::HoldingRegisters, 0}));
    EXPECT_EQ(ref("49999"), (Reference{Table::HoldingRegisters, 9998}));
    EXPECT_EQ(ref("000001"), (Reference{Table::Coils, 0}));
    EXPECT_EQ(ref("065536"), (Reference{Table::Coils, 65535}));
    EXPECT_EQ(ref("400001"), (Reference{Table::HoldingRegisters, 0}));
    EXPECT_EQ(ref("465536"), (Reference{Table::HoldingRegisters, 65535}));
    EXPECT_EQ(ref("310000"), (Reference{Table::InputRegisters, 9999}));
}

TEST(Reference, RejectsInvalid) {
    Reference r;
    for (const char* s :
         {"", "4", "4000", "40000", "400000", "465537", "499999", "20001", "50001", "90001",
          "4000a", "4 001", "-40001", "+40001", "0000001", "4000001", "x0001", "40001 "}) {
        EXPECT_FALSE(parse_reference(s, r)) << s;
    }
}

TEST(Reference, Formats) {
    EXPECT_EQ(format_reference({Table::Coils, 0}), "00001");
    EXPECT_EQ(format_reference({Table::Coils, 9998}), "09999");
    EXPECT_EQ(format_reference({Table::Coils, 9999}), "010000");
    EXPECT_EQ(format_reference({Table::Coils, 65535}), "065536");
    EXPECT_EQ(format_reference({Table::DiscreteInputs, 196}), "10197");
    EXPECT_EQ(format_reference({Table::InputRegisters, 107}), "30108");
    EXPECT_EQ(format_reference({Table::HoldingRegisters, 0}), "40001");
    EXPECT_EQ(format_reference({Table::HoldingRegisters, 65535}), "465536");
    EXPECT_EQ(format_reference({Table::HoldingRegisters, 0}, true), "400001");
    EXPECT_EQ(format_reference({Table::InputRegisters, 99}, true), "300100");
}

TEST(Reference, FormatThenParseRoundTripsEveryOffset) {
    for (Table t :
         {Table::Coils, Table::DiscreteInputs, Table::InputRegisters, Table::HoldingRegisters}) {
        for (std::uint32_t off = 0; off <= 0xFFFF; ++off) {
            const Reference want{t, static_cast<std::uint16_t>(off)};
            for (bool six : {false, true}) {
                Reference back;
                ASSERT_TRUE(parse_reference(format_reference(want, six), back)) << off;
                ASSERT_EQ(back, want);
            }
        }
    }
}

// ---- Hex text

TEST(HexText, AcceptsCommonSpellings) {
    const ByteVec want = {0x01, 0x03, 0x00, 0x00, 0x00, 0x0A, 0xC5, 0xCD};
    for (const char* s : {"01 03 00 00 00 0A C5 CD", "0103000000 0ac5cd", "01030000000AC5CD",
                          "01:03:00:00:00:0A:C5:CD", "0x01 0x03 0x00 0x00 0x00 0x0A 0xC5 0xCD",
                          "0x01030000000AC5CD", "  01-03-00-00-00-0a-c5-cd\n",
                          "01,03,0000,000A,C5CD", "\t01\t0300 00000AC5CD\r\n"}) {
        std::array<std::uint8_t, 16> out{};
        const HexParseResult r = parse_hex(s, out);
        ASSERT_TRUE(r.ok()) << s;
        EXPECT_EQ(ByteVec(out.begin(), out.begin() + static_cast<std::ptrdiff_t>(r.size)), want)
            << s;
    }
    // A group with an odd number of digits is ambiguous, never guessed.
    std::array<std::uint8_t, 16> out{};
    EXPECT_EQ(parse_hex("010300000 00AC5CD", out).error, CodecError::OddHexLength);
}

TEST(HexText, Errors) {
    std::array<std::uint8_t, 4> out{};
    HexParseResult r = parse_hex("", out);
    EXPECT_EQ(r.error, CodecError::Empty);
    EXPECT_EQ(parse_hex("  : ", out).error, CodecError::Empty);
    r = parse_hex("01 0G", out);
    EXPECT_EQ(r.error, CodecError::BadHexDigit);
    EXPECT_EQ(r.position, 4u);
    r = parse_hex("01 003", out);
    EXPECT_EQ(r.error, CodecError::OddHexLength);
    EXPECT_EQ(r.position, 3u);
    EXPECT_EQ(parse_hex("1", out).error, CodecError::OddHexLength);
    EXPECT_EQ(parse_hex("0x", out).error, CodecError::BadHexDigit);
    EXPECT_EQ(parse_hex("0x 01", out).error, CodecError::BadHexDigit);
    EXPECT_EQ(parse_hex("01 xx", out).error, CodecError::BadHexDigit);
    r = parse_hex("01 02 03 04 05", out);
    EXPECT_EQ(r.error, CodecError::BufferTooSmall);
    EXPECT_EQ(r.size, 4u);
    EXPECT_TRUE(parse_hex("01 02 03 04", out).ok());
}

TEST(HexText, FormatsUppercase) {
    const ByteVec b = {0x01, 0x03, 0xAB, 0x0F};
    EXPECT_EQ(format_hex(b), "01 03 AB 0F");
    EXPECT_EQ(format_hex(b, '\0'), "0103AB0F");
    EXPECT_EQ(format_hex(b, ':'), "01:03:AB:0F");
    EXPECT_EQ(format_hex({}), "");
    std::array<std::uint8_t, 4> out{};
    const HexParseResult r = parse_hex(format_hex(b), out);
    ASSERT_TRUE(r.ok());
    EXPECT_EQ(ByteVec(out.begin(), out.end()), b);
}

}  // namespace
}  // namespace mbstorm::codec
