// Every worked frame in the seed documents (three Chinese Modbus tutorials kept beside the
// checkout, in ../shared/seeds, not in it) as a framing test vector:
// RTU frames with their CRC, TCP ADUs with their MBAP header, ASCII renderings with their LRC,
// and the value examples (coil bits, reference numbers, floats). The frames are written here
// as hex, and seed 000's TCP frames are copied as printed into tests/data/seed000_tcp_frames.txt,
// so the suite needs nothing outside the repository.
//
// Where a seed is wrong the Modbus Application Protocol Specification v1.1b3 (and the Serial
// Line Implementation Guide for CRC byte order) wins; each such vector says so and uses the
// corrected frame. PDU contents are tested by the PDU codec suite, not here.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <string>
#include <vector>

#include "codec/ascii.hpp"
#include "codec/mbap.hpp"
#include "codec/rtu.hpp"
#include "codec/values.hpp"
#include "framing_test_support.hpp"

namespace mbstorm::codec {
namespace {

using framing_test::ByteVec;
using framing_test::hex_bytes;
using framing_test::to_vec;

enum class Dir { Request, Response };

struct RtuVector {
    const char* frame;  // address + PDU + CRC as sent on the wire
    Dir dir;
    const char* origin;
};

// Seed 000, part (二) "MODBUS指令说明", slave 0x11. The seed's tables label the first CRC
// byte "CRC高字节" (high byte): the spec transmits the CRC LOW byte first, and the values in
// the tables are in fact in wire order (low byte first) — e.g. 76 87 is CRC 0x8776. The
// vectors below keep wire order.
const RtuVector kSeedRtu[] = {
    {"11 01 00 13 00 25 0E 84", Dir::Request, "000 FC01 query"},
    {"11 01 05 CD 6B B2 0E 1B 45 E6", Dir::Response, "000 FC01 response"},
    {"11 02 00 C4 00 16 BA A9", Dir::Request, "000 FC02 query"},
    {"11 02 03 AC DB 35 20 18", Dir::Response, "000 FC02 response"},
    {"11 03 00 6B 00 03 76 87", Dir::Request, "000 FC03 query"},
    {"11 03 06 00 6B 00 13 00 00 38 B9", Dir::Response, "000 FC03 response"},
    {"11 04 00 08 00 02 F2 99", Dir::Request, "000 FC04 query"},
    {"11 04 04 00 0A 00 0B 8B 80", Dir::Response, "000 FC04 response"},
    {"11 05 00 AC FF 00 4E 8B", Dir::Request, "000 FC05 query"},
    {"11 05 00 AC FF 00 4E 8B", Dir::Response, "000 FC05 response"},
    // Corrected: the seed's table prints the value bytes as 00 01, but its text says the
    // value is 0x0003 and its CRC 9A 9B is the CRC of 11 06 00 01 00 03.
    {"11 06 00 01 00 03 9A 9B", Dir::Request, "000 FC06 query (corrected)"},
    // Corrected: the spec's FC06 response is an echo of the request. The seed prints
    // 11 06 00 01 00 01 1B 5A (CRC-consistent, but not an echo of writing 0x0003).
    {"11 06 00 01 00 03 9A 9B", Dir::Response, "000 FC06 response (corrected)"},
    {"11 0F 00 13 00 0A 02 CD 01 BF 0B", Dir::Request, "000 FC0F query"},
    // Corrected: the spec's FC0F response is address + quantity only, no byte count. The
    // seed prints 11 0F 00 13 00 0A 02 99 1B (a CRC over a stray byte count 02).
    {"11 0F 00 13 00 0A 26 99", Dir::Response, "000 FC0F response (corrected)"},
    {"11 10 00 01 00 02 04 00 0A 01 02 C6 F0", Dir::Request, "000 FC10 query"},
    {"11 10 00 01 00 02 12 98", Dir::Response, "000 FC10 response"},
    // Seed 001 "报文长相": RTU read of 3 HR from 0x006B at slave 1; the seed leaves the CRC
    // as "CRClo CRChi", filled in here (low byte first).
    {"01 03 00 6B 00 03 74 17", Dir::Request, "001 RTU request"},
    {"01 03 06 02 2B 00 00 00 64 05 7A", Dir::Response, "001 RTU response"},
};

std::uint16_t wire_crc(const ByteVec& frame) {
    return static_cast<std::uint16_t>(frame[frame.size() - 2] | (frame[frame.size() - 1] << 8));
}

TEST(SeedRtu, CrcMatchesAndFrameDecodes) {
    for (const auto& v : kSeedRtu) {
        SCOPED_TRACE(v.origin);
        const ByteVec frame = hex_bytes(v.frame);
        EXPECT_EQ(crc16(Bytes(frame.data(), frame.size() - 2)), wire_crc(frame));
        RtuFrame f;
        ASSERT_EQ(decode_rtu_frame(frame, f), CodecError::Ok);
        EXPECT_EQ(f.address, frame[0]);
        EXPECT_EQ(to_vec(f.pdu), ByteVec(frame.begin() + 1, frame.end() - 2));
        // Re-encoding address + PDU gives the same bytes back.
        std::array<std::uint8_t, limits::kMaxRtuAdu> out{};
        const EncodeResult r = encode_rtu_frame(f.address, f.pdu, out);
        ASSERT_TRUE(r.ok());
        EXPECT_EQ(to_vec(Bytes(out.data(), r.size)), frame);
    }
}

TEST(SeedRtu, LengthInferenceFindsTheFrameEnd) {
    for (const auto& v : kSeedRtu) {
        SCOPED_TRACE(v.origin);
        const ByteVec frame = hex_bytes(v.frame);
        const RtuLength len =
            v.dir == Dir::Request ? rtu_request_length(frame) : rtu_response_length(frame);
        ASSERT_EQ(len.status, RtuLength::Status::Known);
        EXPECT_EQ(len.size, frame.size());
    }
}

TEST(SeedRtu, FramesAsPrintedInTheSeedWhereTheyAreWrong) {
    RtuFrame f;
    // FC06 query as printed (value bytes 00 01 with the CRC of value 00 03): the CRC fails.
    EXPECT_EQ(decode_rtu_frame(hex_bytes("11 06 00 01 00 01 9A 9B"), f), CodecError::BadCrc);
    // FC06 response as printed: a valid frame, but not the echo the spec requires.
    const ByteVec seed_rsp = hex_bytes("11 06 00 01 00 01 1B 5A");
    ASSERT_EQ(decode_rtu_frame(seed_rsp, f), CodecError::Ok);
    EXPECT_NE(to_vec(f.pdu), hex_bytes("06 00 01 00 03"));
    // FC0F response as printed: CRC-valid, but 9 bytes where the spec's response is 8.
    const ByteVec seed_0f = hex_bytes("11 0F 00 13 00 0A 02 99 1B");
    ASSERT_EQ(decode_rtu_frame(seed_0f, f), CodecError::Ok);
    EXPECT_EQ(rtu_response_length(seed_0f).size, 8u);
    // Printing the CRC high byte first, as the seed's labels (and seed 002) describe, breaks it.
    EXPECT_EQ(decode_rtu_frame(hex_bytes("11 03 00 6B 00 03 87 76"), f), CodecError::BadCrc);
}

// ---- ASCII: the seeds only describe the format (seed 002: ':' address function data
// LRC-high LRC-low CR LF). The vectors render the seed RTU frames' address + PDU in ASCII;
// the LRCs were computed independently. :1103006B00037E is also the Serial Line guide's
// own example.
struct AsciiVector {
    const char* binary;  // address + PDU
    const char* text;
};
const AsciiVector kSeedAscii[] = {
    {"11 01 00 13 00 25", ":110100130025B6\r\n"},
    {"11 01 05 CD 6B B2 0E 1B", ":110105CD6BB20E1BD6\r\n"},
    {"11 02 00 C4 00 16", ":110200C4001613\r\n"},
    {"11 02 03 AC DB 35", ":110203ACDB352E\r\n"},
    {"11 03 00 6B 00 03", ":1103006B00037E\r\n"},
    {"11 03 06 00 6B 00 13 00 00", ":110306006B0013000068\r\n"},
    {"11 04 00 08 00 02", ":110400080002E1\r\n"},
    {"11 04 04 00 0A 00 0B", ":110404000A000BD2\r\n"},
    {"11 05 00 AC FF 00", ":110500ACFF003F\r\n"},
    {"11 06 00 01 00 03", ":110600010003E5\r\n"},
    {"11 0F 00 13 00 0A 02 CD 01", ":110F0013000A02CD01F3\r\n"},
    {"11 0F 00 13 00 0A", ":110F0013000AC3\r\n"},
    {"11 10 00 01 00 02 04 00 0A 01 02", ":11100001000204000A0102CB\r\n"},
    {"11 10 00 01 00 02", ":111000010002DC\r\n"},
    {"01 03 00 6B 00 03", ":0103006B00038E\r\n"},
    {"01 03 06 02 2B 00 00 00 64", ":010306022B0000006465\r\n"},
};

TEST(SeedAscii, LrcEncodeAndDecode) {
    for (const auto& v : kSeedAscii) {
        SCOPED_TRACE(v.text);
        const ByteVec bin = hex_bytes(v.binary);
        const std::string text = v.text;
        // The last two hex digits before CR LF are the LRC.
        EXPECT_EQ(format_hex(ByteVec{lrc(bin)}), text.substr(text.size() - 4, 2));
        std::array<std::uint8_t, limits::kMaxAsciiAdu> out{};
        const EncodeResult r =
            encode_ascii_frame(bin[0], Bytes(bin.data() + 1, bin.size() - 1), out);
        ASSERT_TRUE(r.ok());
        EXPECT_EQ(std::string(reinterpret_cast<const char*>(out.data()), r.size), text);
        std::array<std::uint8_t, 256> buf{};
        AsciiFrame f;
        ASSERT_EQ(decode_ascii_frame(text, buf, f), CodecError::Ok);
        EXPECT_EQ(f.address, bin[0]);
        EXPECT_EQ(to_vec(f.pdu), ByteVec(bin.begin() + 1, bin.end()));
    }
}

// ---- TCP ADUs from seed 000, part (三) sections 四 (帧结构PDU) and 五
// ("Modbus TCP示例报文") (tests/data/seed000_tcp_frames.txt
// holds them as printed). Where a frame disagrees with the Modbus Application Protocol
// Specification v1.1b3 (and the Messaging on TCP/IP guide for MBAP), the spec wins: the vector
// is the corrected frame, `as_printed` the seed's text, and the comment says why.
struct TcpVector {
    const char* adu;
    const char* as_printed;  // the seed's text, to prove the vector comes from it
};
const TcpVector kSeedTcp[] = {
    {"00 01 00 00 00 06 01 01 00 02 00 08", nullptr},
    {"00 01 00 00 00 04 01 01 01 01", nullptr},
    {"00 01 00 00 00 06 01 05 00 03 FF 00", nullptr},
    {"00 01 00 00 00 06 01 02 00 00 00 12", nullptr},
    {"00 01 00 00 00 06 01 02 03 01 04 00", nullptr},
    {"00 01 00 00 00 06 01 04 00 02 00 05", nullptr},
    {"00 01 00 00 00 0D 01 04 0A 00 0C 00 00 00 00 00 00 00 00", nullptr},
    {"00 01 00 00 00 06 01 03 00 00 00 03", nullptr},
    {"00 01 00 00 00 09 01 03 06 00 21 00 00 00 00", nullptr},
    {"00 01 00 00 00 06 01 06 00 00 00 0A", nullptr},
    // Corrected: the seed's FC10 request is cut short ("... 02 00 0"); its text says the
    // value written is 0x000F, and the MBAP length 9 needs that last byte.
    {"00 01 00 00 00 09 01 10 00 00 00 01 02 00 0F", "00 01 00 00 00 09 01 10 00 00 00 01 02 00 0"},
    {"00 01 00 00 00 06 01 10 00 00 00 01", nullptr},
    // The seed's explanation table gives the transaction id low byte as 0x96, but the frame
    // bytes (and its reply) say 0x76: the frames win, tid = 0x9776.
    {"97 76 00 00 00 06 04 04 00 7D 00 7D", nullptr},
    {"97 79 00 00 00 09 04 10 00 00 00 01 02 00 01", nullptr},
    {"97 79 00 00 00 06 04 10 00 00 00 01", nullptr},
};

// The seed's TCP frames exactly as it prints them, copied into the repository (the file says
// from where), one frame a line. A missing or short file fails the tests that read it.
std::vector<std::string> seed_tcp_lines() {
    std::ifstream in(MBSTORM_SOURCE_DIR "/tests/data/seed000_tcp_frames.txt");
    std::vector<std::string> lines;
    for (std::string line; std::getline(in, line);)
        if (!line.empty() && line[0] != '#') lines.push_back(line);
    return lines;
}

// The 259-byte FC04 reply to "read 125 input registers" (seed 000, part (三) section 五, example
// 2).
std::string long_reply_text() {
    for (const std::string& line : seed_tcp_lines())
        if (line.starts_with("97 76 00 00 00 FD")) return line;
    return {};
}

TEST(SeedTcp, VectorsAreTakenFromTheSeed) {
    const std::vector<std::string> lines = seed_tcp_lines();
    // 14 frames in section 四 (two echoes printed twice), 4 in section 五.
    ASSERT_EQ(lines.size(), 18u) << "tests/data/seed000_tcp_frames.txt";
    for (const auto& v : kSeedTcp) {
        const char* printed = v.as_printed ? v.as_printed : v.adu;
        EXPECT_NE(std::find(lines.begin(), lines.end(), printed), lines.end()) << printed;
    }
    // And no frame of the seed is left out: each line is a vector or the long reply.
    for (const std::string& line : lines) {
        const bool vector = std::any_of(std::begin(kSeedTcp), std::end(kSeedTcp), [&](auto& v) {
            return line == (v.as_printed ? v.as_printed : v.adu);
        });
        EXPECT_TRUE(vector || line == long_reply_text()) << line;
    }
}

TEST(SeedTcp, HeadersAndFramesDecode) {
    for (const auto& v : kSeedTcp) {
        SCOPED_TRACE(v.adu);
        const ByteVec a = hex_bytes(v.adu);
        TcpFrame f;
        ASSERT_EQ(decode_tcp_frame(a, f), CodecError::Ok);
        EXPECT_EQ(f.header.protocol_id, 0);
        EXPECT_EQ(f.header.length, a.size() - 6);
        EXPECT_EQ(f.header.unit_id, a[6]);
        EXPECT_EQ(to_vec(f.pdu), ByteVec(a.begin() + 7, a.end()));
        std::array<std::uint8_t, limits::kMaxTcpAdu> out{};
        const EncodeResult r =
            encode_tcp_frame(f.header.transaction_id, f.header.unit_id, f.pdu, out);
        ASSERT_TRUE(r.ok());
        EXPECT_EQ(to_vec(Bytes(out.data(), r.size)), a);
    }
    TcpFrame f;
    ASSERT_EQ(decode_tcp_frame(hex_bytes("97 76 00 00 00 06 04 04 00 7D 00 7D"), f),
              CodecError::Ok);
    EXPECT_EQ(f.header.transaction_id, 0x9776);
}

TEST(SeedTcp, TruncatedFc10RequestAsPrinted) {
    // "00 0" is not even whole bytes; the 14 whole bytes fall one short of MBAP length 9.
    ByteVec buf(32);
    EXPECT_EQ(parse_hex("00 01 00 00 00 09 01 10 00 00 00 01 02 00 0", buf).error,
              CodecError::OddHexLength);
    const ByteVec cut = hex_bytes("00 01 00 00 00 09 01 10 00 00 00 01 02 00");
    TcpFrame f;
    EXPECT_EQ(decode_tcp_frame(cut, f), CodecError::LengthMismatch);
    MbapSplitter sp;
    sp.feed(cut);
    EXPECT_EQ(sp.next(f), MbapSplitter::Status::NeedMore);
    EXPECT_EQ(sp.buffered(), cut.size());
}

TEST(SeedTcp, MaximumSizeReplyAndItsFloats) {
    const std::string text = long_reply_text();
    ASSERT_FALSE(text.empty()) << "tests/data/seed000_tcp_frames.txt has no 259-byte reply";
    const ByteVec a = hex_bytes(text);
    // Seed 000 claims "TCP MODBUS ADU = 249 字节 + MBAP (7 字节) = 256 字节": the spec's PDU
    // is up to 253 bytes, so a TCP ADU is up to 260 — and this very reply is 259 bytes.
    ASSERT_EQ(a.size(), 259u);
    EXPECT_EQ(limits::kMaxTcpAdu, 260u);
    TcpFrame f;
    ASSERT_EQ(decode_tcp_frame(a, f), CodecError::Ok);
    EXPECT_EQ(f.header.length, 0xFD);
    ASSERT_EQ(f.pdu[1], 0xFA);  // 250 bytes = 125 registers
    // The registers hold floats low word first (CDAB).
    std::vector<std::uint16_t> regs;
    for (std::size_t i = 2; i + 1 < f.pdu.size(); i += 2) regs.push_back(load_be16(&f.pdu[i]));
    ASSERT_EQ(regs.size(), 125u);
    const float want[] = {9.5419f, 1.16f, 1.16f, 1.18f, 1.19f, -3.7f};
    for (std::size_t i = 0; i < std::size(want); ++i) {
        const float got =
            f32_from_registers(std::span<const std::uint16_t, 2>(&regs[2 * i], 2), WordOrder::CDAB);
        EXPECT_NEAR(got, want[i], 1e-4) << i;
    }
}

TEST(SeedTcp, PipelinedSeedStreamSplitsAtEverySplitPoint) {
    ByteVec stream;
    std::vector<ByteVec> want;
    for (const auto& v : kSeedTcp) want.push_back(hex_bytes(v.adu));
    const std::string long_text = long_reply_text();
    ASSERT_FALSE(long_text.empty());
    want.insert(want.begin() + 13, hex_bytes(long_text));
    for (const auto& a : want) stream.insert(stream.end(), a.begin(), a.end());
    for (std::size_t cut = 0; cut <= stream.size(); ++cut) {
        MbapSplitter sp;
        std::vector<ByteVec> got;
        for (const Bytes chunk :
             {Bytes(stream.data(), cut), Bytes(stream.data() + cut, stream.size() - cut)}) {
            sp.feed(chunk);
            TcpFrame f;
            MbapSplitter::Status st;
            while ((st = sp.next(f)) == MbapSplitter::Status::Frame) got.push_back(to_vec(f.adu));
            ASSERT_EQ(st, MbapSplitter::Status::NeedMore);
        }
        ASSERT_EQ(got, want) << "cut " << cut;
    }
}

// ---- Values from the seeds.

TEST(SeedValues, CoilBitsOfTheFc01Example) {
    // Seed 000: coils 0x0013..0x0037 (37 coils) -> CD 6B B2 0E 1B, LSB = lowest coil,
    // the three unused bits of the last byte zero.
    const ByteVec data = hex_bytes("CD 6B B2 0E 1B");
    std::array<bool, 37> coils{};
    ASSERT_TRUE(unpack_bits(data, coils));
    // 0x001A..0x0013 = ON ON OFF OFF ON ON OFF ON
    const bool first[] = {true, false, true, true, false, false, true, true};  // 0x13 upward
    for (int i = 0; i < 8; ++i) EXPECT_EQ(coils[i], first[i]) << i;
    // 0x0037..0x0033 = ON ON OFF ON ON
    const bool last[] = {true, true, false, true, true};  // 0x33 upward
    for (int i = 0; i < 5; ++i) EXPECT_EQ(coils[32 + i], last[i]) << i;
    EXPECT_TRUE(padding_is_zero(data, 37));
    std::array<std::uint8_t, 5> back{};
    ASSERT_TRUE(pack_bits(coils, back).ok());
    EXPECT_EQ(ByteVec(back.begin(), back.end()), data);
}

TEST(SeedValues, DiscreteInputBitsOfTheFc02Example) {
    // Seed 000: inputs 0x00C4..0x00D9 (22) -> AC DB 35. The seed's bit tables for the first
    // two bytes are wrong (they show 0011 0101 and 1110 1011, i.e. 0x35 and 0xEB); per the
    // spec's own example byte 0xAC means inputs 0xCB..0xC4 = 1010 1100.
    const ByteVec data = hex_bytes("AC DB 35");
    std::array<bool, 22> in{};
    ASSERT_TRUE(unpack_bits(data, in));
    const bool c4_to_cb[] = {false, false, true, true, false, true, false, true};
    for (int i = 0; i < 8; ++i) EXPECT_EQ(in[i], c4_to_cb[i]) << i;
    // 0x00D9..0x00D4 = ON ON OFF ON OFF ON, 0xDA and 0xDB padding.
    const bool d4_to_d9[] = {true, false, true, false, true, true};
    for (int i = 0; i < 6; ++i) EXPECT_EQ(in[16 + i], d4_to_d9[i]) << i;
    EXPECT_TRUE(padding_is_zero(data, 22));
}

TEST(SeedValues, Fc02TcpExampleBits) {
    // Seed 000 TCP: 18 inputs -> 01 04 00: the 1st and the 11th input are ON.
    const ByteVec data = hex_bytes("01 04 00");
    for (std::size_t i = 0; i < 18; ++i) EXPECT_EQ(bit_at(data, i), i == 0 || i == 10) << i;
}

TEST(SeedValues, ReferenceNumbers) {
    // Seed 001 worked examples.
    Reference r;
    ASSERT_TRUE(parse_reference("40100", r));
    EXPECT_EQ(r, (Reference{Table::HoldingRegisters, 99}));
    ASSERT_TRUE(parse_reference("00020", r));
    EXPECT_EQ(r, (Reference{Table::Coils, 19}));
    ASSERT_TRUE(parse_reference("10001", r));
    EXPECT_EQ(r, (Reference{Table::DiscreteInputs, 0}));
    ASSERT_TRUE(parse_reference("10016", r));
    EXPECT_EQ(r.offset, 15);  // 10001-10016 is 16 inputs from offset 0
    EXPECT_EQ(format_reference({Table::HoldingRegisters, 0x006B}), "40108");
    // Seed 000 "ModbusTCP协议分析": offsets and the reference numbers it gives them.
    EXPECT_EQ(format_reference({Table::Coils, 0x13}), "00020");
    EXPECT_EQ(format_reference({Table::Coils, 0x13 + 0x1B - 1}), "00046");
    EXPECT_EQ(format_reference({Table::DiscreteInputs, 0xC4}), "10197");
    EXPECT_EQ(format_reference({Table::DiscreteInputs, 0xC4 + 0x1D - 1}), "10225");
    EXPECT_EQ(format_reference({Table::HoldingRegisters, 0x6B}), "40108");
    EXPECT_EQ(format_reference({Table::InputRegisters, 0x6B}), "30108");
    EXPECT_EQ(format_reference({Table::Coils, 0xAC}), "00173");
    EXPECT_EQ(format_reference({Table::HoldingRegisters, 0x87}), "40136");
}

TEST(SeedValues, FloatOverTwoHoldingRegistersLowWordFirst) {
    // Seed 001 example 4: "40100 (low word) and 40101 (high word) form one float" -> FC03,
    // offset 99, quantity 2, low word in the first register: word order CDAB. Seed 002's
    // analog registers (1010 low 16 bits, 1011 high 16 bits) use the same layout.
    Reference r;
    ASSERT_TRUE(parse_reference("40100", r));
    EXPECT_EQ(r.offset, 99);
    const Registers2 regs = {0xE979, 0x42F6};  // 40100 = low word, 40101 = high word
    EXPECT_EQ(f32_from_registers(regs, WordOrder::CDAB), 123.456f);
    EXPECT_EQ(registers_from_f32(123.456f, WordOrder::CDAB), regs);
    // Read the wrong way (ABCD) the same registers mean something else entirely.
    EXPECT_NE(f32_from_registers(regs, WordOrder::ABCD), 123.456f);
}

}  // namespace
}  // namespace mbstorm::codec
