// Encoders: exact bytes from fields, validation (InvalidArgument), BufferTooSmall at every
// size, allow_invalid for the fuzzer, and payloads built in place in the output buffer.
#include <gtest/gtest.h>

#include <array>
#include <cstring>

#include "codec/limits.hpp"
#include "pdu_test_support.hpp"

namespace mbstorm::codec::test {
namespace {

std::string encode_req_hex(const Request& r, bool allow_invalid = false) {
    std::uint8_t buf[300];
    const EncodeResult e = encode_request(r, MutableBytes(buf, sizeof buf), allow_invalid);
    if (!e.ok()) return std::string(error_name(e.error));
    return to_hex(Bytes(buf, e.size));
}

std::string encode_rsp_hex(const Response& r) {
    std::uint8_t buf[300];
    const EncodeResult e = encode_response(r, MutableBytes(buf, sizeof buf));
    if (!e.ok()) return std::string(error_name(e.error));
    return to_hex(Bytes(buf, e.size));
}

Request req(std::uint8_t fc) {
    Request r;
    r.function = fc;
    return r;
}

TEST(RequestEncode, FromFields) {
    Request r = req(0x03);
    r.address = 0x006B;
    r.quantity = 3;
    EXPECT_EQ(encode_req_hex(r), "03 00 6B 00 03");
    r = req(0x05);
    r.address = 0xAC;
    r.value = 0xFF00;
    EXPECT_EQ(encode_req_hex(r), "05 00 AC FF 00");
    EXPECT_EQ(encode_req_hex(req(0x07)), "07");
    r = req(0x08);
    r.sub_function = 0x000B;
    const ByteVec zero = hex("00 00");
    r.payload = view(zero);
    EXPECT_EQ(encode_req_hex(r), "08 00 0B 00 00");
    r = req(0x10);
    r.address = 1;
    r.quantity = 2;
    const ByteVec regs = hex("00 0A 01 02");
    r.payload = view(regs);
    EXPECT_EQ(encode_req_hex(r), "10 00 01 00 02 04 00 0A 01 02");
    r = req(0x16);
    r.address = 4;
    r.and_mask = 0xF2;
    r.or_mask = 0x25;
    EXPECT_EQ(encode_req_hex(r), "16 00 04 00 F2 00 25");
    r = req(0x17);
    r.address = 3;
    r.quantity = 6;
    r.write_address = 0x0E;
    r.write_quantity = 2;
    r.payload = view(regs);
    EXPECT_EQ(encode_req_hex(r), "17 00 03 00 06 00 0E 00 02 04 00 0A 01 02");
    r = req(0x18);
    r.address = 0x04DE;
    EXPECT_EQ(encode_req_hex(r), "18 04 DE");
    r = req(0x2B);
    r.mei_type = 0x0E;
    r.device_id_code = 1;
    EXPECT_EQ(encode_req_hex(r), "2B 0E 01 00");
    const ByteVec subs = hex("06 00 04 00 01 00 02");
    r = req(0x14);
    r.payload = view(subs);
    EXPECT_EQ(encode_req_hex(r), "14 07 06 00 04 00 01 00 02");
}

TEST(RequestEncode, ValidationMatchesDecoder) {
    Request r = req(0x03);
    r.quantity = 0;
    EXPECT_EQ(encode_req_hex(r), "invalid_argument");
    r.quantity = 126;
    EXPECT_EQ(encode_req_hex(r), "invalid_argument");
    r.quantity = 2;
    r.address = 0xFFFF;
    EXPECT_EQ(encode_req_hex(r), "invalid_argument");
    r = req(0x01);
    r.quantity = 2000;
    EXPECT_EQ(encode_req_hex(r), "01 00 00 07 D0");
    r.quantity = 2001;
    EXPECT_EQ(encode_req_hex(r), "invalid_argument");
    r = req(0x05);
    r.value = 1;
    EXPECT_EQ(encode_req_hex(r), "invalid_argument");
    r = req(0x0F);
    r.quantity = 10;
    const ByteVec one = hex("CD");
    r.payload = view(one);  // 10 coils need 2 bytes
    EXPECT_EQ(encode_req_hex(r), "invalid_argument");
    r = req(0x08);
    r.sub_function = 0x13;
    EXPECT_EQ(encode_req_hex(r), "invalid_argument");
    r = req(0x2B);
    r.mei_type = 0x0D;
    EXPECT_EQ(encode_req_hex(r), "invalid_argument");
    EXPECT_EQ(encode_req_hex(req(0x41)), "invalid_argument");
    EXPECT_EQ(encode_req_hex(req(0x00)), "invalid_argument");
    ByteVec huge(300, 0);
    r = req(0x10);
    r.quantity = 150;
    r.payload = view(huge);
    EXPECT_EQ(encode_req_hex(r, true), "invalid_argument");  // byte count cannot hold it
}

TEST(RequestEncode, AllowInvalidWritesOutOfSpecRequests) {
    Request r = req(0x03);
    r.quantity = 0;
    EXPECT_EQ(encode_req_hex(r, true), "03 00 00 00 00");
    r.address = 0xFFFF;
    r.quantity = 0x7D0;
    EXPECT_EQ(encode_req_hex(r, true), "03 FF FF 07 D0");
    r = req(0x05);
    r.value = 0x1234;
    EXPECT_EQ(encode_req_hex(r, true), "05 00 00 12 34");
    const ByteVec junk = hex("DE AD");
    r = req(0x41);
    r.payload = view(junk);
    EXPECT_EQ(encode_req_hex(r, true), "41 DE AD");
    r = req(0x2B);
    r.mei_type = 0x0D;
    r.payload = view(junk);
    EXPECT_EQ(encode_req_hex(r, true), "2B 0D DE AD");
    r = req(0x0F);
    r.quantity = 10;
    const ByteVec one = hex("CD");
    r.payload = view(one);
    EXPECT_EQ(encode_req_hex(r, true), "0F 00 00 00 0A 01 CD");
}

// Encoding into every buffer shorter than the PDU fails without writing past it.
void expect_buffer_too_small_below(const ByteVec& pdu, bool is_request) {
    Request rq;
    Response rs;
    if (is_request) {
        ASSERT_TRUE(decode_request(view(pdu), rq).ok()) << to_hex(view(pdu));
    } else {
        ASSERT_EQ(decode_response(view(pdu), rs), CodecError::Ok) << to_hex(view(pdu));
    }
    for (std::size_t cap = 0; cap < pdu.size(); ++cap) {
        std::array<std::uint8_t, 300> buf;
        buf.fill(0xEE);
        const MutableBytes out(buf.data(), cap);
        const EncodeResult e = is_request ? encode_request(rq, out) : encode_response(rs, out);
        EXPECT_EQ(e.error, CodecError::BufferTooSmall) << to_hex(view(pdu)) << " cap " << cap;
        for (std::size_t i = cap; i < buf.size(); ++i) ASSERT_EQ(buf[i], 0xEE) << "wrote past";
    }
}

TEST(Encode, BufferTooSmallForEveryFunction) {
    const char* requests[] = {
        "01 00 13 00 25",
        "02 00 C4 00 16",
        "03 00 6B 00 03",
        "04 00 08 00 01",
        "05 00 AC FF 00",
        "06 00 01 00 03",
        "07",
        "08 00 00 12 34",
        "08 00 0A 00 00",
        "0B",
        "0C",
        "0F 00 13 00 0A 02 CD 01",
        "10 00 01 00 02 04 00 0A 01 02",
        "11",
        "14 07 06 00 04 00 01 00 02",
        "15 09 06 00 04 00 07 00 01 AB CD",
        "16 00 04 00 F2 00 25",
        "17 00 03 00 06 00 0E 00 02 04 00 0A 01 02",
        "18 04 DE",
        "2B 0E 01 00",
    };
    for (const char* h : requests) expect_buffer_too_small_below(hex(h), true);
    const char* responses[] = {
        "01 05 CD 6B B2 0E 1B",
        "02 03 AC DB 35",
        "03 06 02 2B 00 00 00 64",
        "04 02 00 0A",
        "05 00 AC FF 00",
        "06 00 01 00 03",
        "07 6D",
        "08 00 00 12 34",
        "0B 00 00 01 08",
        "0C 08 00 00 01 08 01 21 20 00",
        "0F 00 13 00 0A",
        "10 00 01 00 02",
        "11 02 0A FF",
        "14 06 05 06 0D FE 00 20",
        "15 09 06 00 04 00 07 00 01 AB CD",
        "16 00 04 00 F2 00 25",
        "17 02 00 FE",
        "18 00 06 00 02 01 B8 12 84",
        "2B 0E 01 01 00 00 01 00 02 41 42",
        "83 02",
    };
    for (const char* h : responses) expect_buffer_too_small_below(hex(h), false);
}

TEST(Encode, ReadRequestFastPath) {
    std::uint8_t buf[5];
    EncodeResult e = encode_read_request(0x03, 0x1234, 125, MutableBytes(buf, 5));
    ASSERT_TRUE(e.ok());
    EXPECT_EQ(to_hex(Bytes(buf, e.size)), "03 12 34 00 7D");
    e = encode_read_request(0x03, 0, 1, MutableBytes(buf, 4));
    EXPECT_EQ(e.error, CodecError::BufferTooSmall);
}

TEST(ResponseEncode, FromFields) {
    Response r;
    r.function = 0x03;
    const ByteVec regs = hex("02 2B 00 00 00 64");
    r.payload = view(regs);
    EXPECT_EQ(encode_rsp_hex(r), "03 06 02 2B 00 00 00 64");
    r = Response{};
    r.function = 0x0F;
    r.address = 0x13;
    r.quantity = 10;
    EXPECT_EQ(encode_rsp_hex(r), "0F 00 13 00 0A");
    r = Response{};
    r.function = 0x18;
    r.fifo_count = 2;
    const ByteVec fifo = hex("01 B8 12 84");
    r.payload = view(fifo);
    EXPECT_EQ(encode_rsp_hex(r), "18 00 06 00 02 01 B8 12 84");
    r.fifo_count = 3;  // payload disagrees
    EXPECT_EQ(encode_rsp_hex(r), "invalid_argument");
    r.fifo_count = 32;
    EXPECT_EQ(encode_rsp_hex(r), "invalid_argument");
    r = Response{};
    r.function = 0x0C;
    r.event_count = 0x108;
    r.message_count = 0x121;
    const ByteVec events = hex("20 00");
    r.payload = view(events);
    EXPECT_EQ(encode_rsp_hex(r), "0C 08 00 00 01 08 01 21 20 00");
    r = Response{};
    r.function = 0x2B;
    r.mei_type = 0x0E;
    r.device_id_code = 4;
    r.conformity_level = 0x81;
    r.object_count = 1;
    const ByteVec obj = hex("05 02 41 42");
    r.payload = view(obj);
    EXPECT_EQ(encode_rsp_hex(r), "2B 0E 04 81 00 00 01 05 02 41 42");
    r.object_count = 2;
    EXPECT_EQ(encode_rsp_hex(r), "invalid_argument");
}

TEST(ResponseEncode, ValidationMatchesDecoder) {
    Response r;
    r.function = 0x03;
    const ByteVec odd = hex("01 02 03");
    r.payload = view(odd);
    EXPECT_EQ(encode_rsp_hex(r), "invalid_argument");
    r.payload = {};
    EXPECT_EQ(encode_rsp_hex(r), "invalid_argument");
    ByteVec too_many(252, 0);
    r.payload = view(too_many);
    EXPECT_EQ(encode_rsp_hex(r), "invalid_argument");
    r = Response{};
    r.function = 0x05;
    r.value = 0x00FF;
    EXPECT_EQ(encode_rsp_hex(r), "invalid_argument");
    r = Response{};
    r.function = 0x10;
    r.quantity = 124;
    EXPECT_EQ(encode_rsp_hex(r), "invalid_argument");
    r = Response{};
    r.function = 0x41;
    EXPECT_EQ(encode_rsp_hex(r), "invalid_argument");
    r = Response{};
    r.function = 0x2B;
    r.mei_type = 0x0D;
    EXPECT_EQ(encode_rsp_hex(r), "invalid_argument");
}

TEST(ResponseEncode, ExceptionViaResponseAndDirect) {
    Response r;
    r.function = 0x03;
    r.exception = ExceptionCode::IllegalDataAddress;
    EXPECT_EQ(encode_rsp_hex(r), "83 02");
    std::uint8_t buf[2];
    EncodeResult e = encode_exception(0x41, ExceptionCode::IllegalFunction, MutableBytes(buf, 2));
    ASSERT_TRUE(e.ok());
    EXPECT_EQ(to_hex(Bytes(buf, 2)), "C1 01");
    e = encode_exception(0x03, ExceptionCode::None, MutableBytes(buf, 2));
    EXPECT_EQ(e.error, CodecError::InvalidArgument);
    e = encode_exception(0x83, ExceptionCode::IllegalFunction, MutableBytes(buf, 2));
    EXPECT_EQ(e.error, CodecError::InvalidArgument);
    e = encode_exception(0x03, ExceptionCode::IllegalFunction, MutableBytes(buf, 1));
    EXPECT_EQ(e.error, CodecError::BufferTooSmall);
}

// A server builds register data straight into its send buffer, then frames it in place.
TEST(ResponseEncode, PayloadAlreadyInOutputBuffer) {
    std::uint8_t buf[260];
    for (int i = 0; i < 250; ++i) buf[2 + i] = static_cast<std::uint8_t>(i);
    Response r;
    r.function = 0x03;
    r.payload = Bytes(buf + 2, 250);
    const EncodeResult e = encode_response(r, MutableBytes(buf, sizeof buf));
    ASSERT_TRUE(e.ok());
    EXPECT_EQ(e.size, 252u);
    EXPECT_EQ(buf[0], 0x03);
    EXPECT_EQ(buf[1], 250);
    for (int i = 0; i < 250; ++i) ASSERT_EQ(buf[2 + i], i);

    // Overlap the other way: the payload starts where the head goes.
    for (int i = 0; i < 4; ++i) buf[i] = static_cast<std::uint8_t>(0xA0 + i);
    r.payload = Bytes(buf, 4);
    const EncodeResult e2 = encode_response(r, MutableBytes(buf, sizeof buf));
    ASSERT_TRUE(e2.ok());
    EXPECT_EQ(to_hex(Bytes(buf, e2.size)), "03 04 A0 A1 A2 A3");

    std::uint8_t rq[16] = {0, 0, 0, 0, 0, 0, 0xCD, 0x01};
    Request w;
    w.function = 0x0F;
    w.address = 0x13;
    w.quantity = 10;
    w.payload = Bytes(rq + 6, 2);
    const EncodeResult e3 = encode_request(w, MutableBytes(rq, sizeof rq));
    ASSERT_TRUE(e3.ok());
    EXPECT_EQ(to_hex(Bytes(rq, e3.size)), "0F 00 13 00 0A 02 CD 01");
}

// FC15's sub-requests written one after another read back with the iterator, and the
// request around them is the specification's example.
TEST(PduEncode, FileSubRequestsReadBackAndMakeTheSpecExample) {
    const std::uint8_t data[] = {0x06, 0xAF, 0x04, 0xBE, 0x10, 0x0D};
    FileSubRequest sub{limits::kFileReferenceType, 4, 7, 3, Bytes(data, sizeof data)};
    std::uint8_t payload[16];
    const EncodeResult written =
        encode_file_sub_request(sub, MutableBytes(payload, sizeof payload));
    ASSERT_TRUE(written.ok());
    EXPECT_EQ(written.size, 13u);
    Request r;
    r.function = 0x15;
    r.payload = Bytes(payload, written.size);
    EXPECT_EQ(encode_req_hex(r), "15 0D 06 00 04 00 07 00 03 06 AF 04 BE 10 0D");
    FileRecordIterator it(r.payload, true);
    FileSubRequest back;
    ASSERT_EQ(it.next(back), CodecError::Ok);
    EXPECT_EQ(back.file_number, 4);
    EXPECT_EQ(back.record_number, 7);
    EXPECT_EQ(back.record_length, 3);
    EXPECT_EQ(to_hex(back.record_data), "06 AF 04 BE 10 0D");
    EXPECT_EQ(it.next(back), CodecError::Empty);
    EXPECT_EQ(encode_file_sub_request(sub, MutableBytes(payload, 12)).error,
              CodecError::BufferTooSmall);
}

}  // namespace
}  // namespace mbstorm::codec::test
