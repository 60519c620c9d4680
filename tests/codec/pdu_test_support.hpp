// Helpers shared by the PDU tests: hex parsing, PDU builders and round-trip checks.
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "codec/pdu.hpp"

namespace mbstorm::codec::test {

using ByteVec = std::vector<std::uint8_t>;

// "01 03 00 6B" (spaces optional) -> bytes. Aborts the test on bad input.
inline ByteVec hex(std::string_view text) {
    ByteVec out;
    int high = -1;
    for (char c : text) {
        int v;
        if (c >= '0' && c <= '9') {
            v = c - '0';
        } else if (c >= 'a' && c <= 'f') {
            v = c - 'a' + 10;
        } else if (c >= 'A' && c <= 'F') {
            v = c - 'A' + 10;
        } else {
            continue;
        }
        if (high < 0) {
            high = v;
        } else {
            out.push_back(static_cast<std::uint8_t>(high * 16 + v));
            high = -1;
        }
    }
    EXPECT_EQ(high, -1) << "odd number of hex digits in " << text;
    return out;
}

inline std::string to_hex(Bytes b) {
    static constexpr char kDigits[] = "0123456789ABCDEF";
    std::string s;
    for (std::uint8_t x : b) {
        if (!s.empty()) s.push_back(' ');
        s.push_back(kDigits[x >> 4]);
        s.push_back(kDigits[x & 15]);
    }
    return s;
}

inline Bytes view(const ByteVec& v) {
    return Bytes(v.data(), v.size());
}

inline void put16(ByteVec& v, std::uint16_t x) {
    v.push_back(static_cast<std::uint8_t>(x >> 8));
    v.push_back(static_cast<std::uint8_t>(x));
}

// fc, address, quantity (FC01-04 requests, FC0F/10 responses, FC05/06 both ways).
inline ByteVec pdu_addr_qty(std::uint8_t fc, std::uint16_t a, std::uint16_t q) {
    ByteVec v{fc};
    put16(v, a);
    put16(v, q);
    return v;
}

// FC0F/10 request with `byte_count` and that many filler bytes.
inline ByteVec pdu_write_multiple(std::uint8_t fc, std::uint16_t a, std::uint16_t q,
                                  std::size_t byte_count) {
    ByteVec v = pdu_addr_qty(fc, a, q);
    v.push_back(static_cast<std::uint8_t>(byte_count));
    for (std::size_t i = 0; i < byte_count; ++i) v.push_back(static_cast<std::uint8_t>(i * 7));
    return v;
}

// FC17 request with a byte count of 2 * write quantity.
inline ByteVec pdu_read_write(std::uint16_t ra, std::uint16_t rq, std::uint16_t wa,
                              std::uint16_t wq) {
    ByteVec v{0x17};
    put16(v, ra);
    put16(v, rq);
    put16(v, wa);
    put16(v, wq);
    v.push_back(static_cast<std::uint8_t>(2 * wq));
    for (int i = 0; i < 2 * wq; ++i) v.push_back(static_cast<std::uint8_t>(i));
    return v;
}

// One FC14/15 sub-request; FC15 (`data_words` >= 0) appends that many registers.
inline void add_file_sub(ByteVec& v, std::uint8_t ref, std::uint16_t file, std::uint16_t record,
                         std::uint16_t length, bool with_data) {
    v.push_back(ref);
    put16(v, file);
    put16(v, record);
    put16(v, length);
    if (with_data) {
        for (int i = 0; i < length; ++i) put16(v, static_cast<std::uint16_t>(0x1000 + i));
    }
}

// Wraps sub-requests as an FC14/15 PDU.
inline ByteVec pdu_file(std::uint8_t fc, const ByteVec& subs) {
    ByteVec v{fc, static_cast<std::uint8_t>(subs.size())};
    v.insert(v.end(), subs.begin(), subs.end());
    return v;
}

// Decodes a request that must be valid, re-encodes it and expects identical bytes.
inline Request expect_request_round_trip(const ByteVec& pdu) {
    Request req;
    const RequestStatus st = decode_request(view(pdu), req);
    EXPECT_TRUE(st.ok()) << to_hex(view(pdu)) << " -> " << error_name(st.error);
    EXPECT_EQ(st.exception, ExceptionCode::None);
    std::uint8_t buf[300];
    const EncodeResult enc = encode_request(req, MutableBytes(buf, sizeof buf));
    EXPECT_TRUE(enc.ok()) << to_hex(view(pdu)) << " -> " << error_name(enc.error);
    EXPECT_EQ(to_hex(Bytes(buf, enc.size)), to_hex(view(pdu)));
    return req;
}

inline Response expect_response_round_trip(const ByteVec& pdu) {
    Response rsp;
    const CodecError e = decode_response(view(pdu), rsp);
    EXPECT_EQ(e, CodecError::Ok) << to_hex(view(pdu)) << " -> " << error_name(e);
    std::uint8_t buf[300];
    const EncodeResult enc = encode_response(rsp, MutableBytes(buf, sizeof buf));
    EXPECT_TRUE(enc.ok()) << to_hex(view(pdu)) << " -> " << error_name(enc.error);
    EXPECT_EQ(to_hex(Bytes(buf, enc.size)), to_hex(view(pdu)));
    return rsp;
}

inline RequestStatus decode_req(const ByteVec& pdu) {
    Request req;
    return decode_request(view(pdu), req);
}

inline CodecError decode_rsp(const ByteVec& pdu) {
    Response rsp;
    return decode_response(view(pdu), rsp);
}

// Expects decode_request to fail with `error` and owe `exception`.
#define EXPECT_REQUEST_FAILS(pdu, err, exc)                                       \
    do {                                                                          \
        const auto st_ = ::mbstorm::codec::test::decode_req(pdu);                 \
        EXPECT_EQ(st_.error, err) << ::mbstorm::codec::test::to_hex(              \
            ::mbstorm::codec::test::view(pdu));                                   \
        EXPECT_EQ(st_.exception, exc)                                             \
            << ::mbstorm::codec::test::to_hex(::mbstorm::codec::test::view(pdu)); \
    } while (0)

}  // namespace mbstorm::codec::test
