// Round trips for every function code, and the property behind them: whatever
// decode_request/decode_response accept re-encodes to exactly the same bytes.
#include <gtest/gtest.h>

#include <random>

#include "codec/limits.hpp"
#include "pdu_test_support.hpp"
#include "pdu_vectors.hpp"

namespace mbstorm::codec::test {
namespace {

TEST(RoundTrip, EveryValidRequest) {
    for (const char* h : kValidRequests) {
        SCOPED_TRACE(h);
        expect_request_round_trip(hex(h));
    }
}

TEST(RoundTrip, EveryValidResponse) {
    for (const char* h : kValidResponses) {
        SCOPED_TRACE(h);
        expect_response_round_trip(hex(h));
    }
}

TEST(RoundTrip, VectorsCoverEverySupportedFunction) {
    for (int fc = 0; fc < 256; ++fc) {
        if (!is_supported_function(static_cast<std::uint8_t>(fc))) continue;
        bool in_requests = false;
        bool in_responses = false;
        for (const char* h : kValidRequests) in_requests |= hex(h)[0] == fc;
        for (const char* h : kValidResponses) in_responses |= hex(h)[0] == fc;
        EXPECT_TRUE(in_requests) << fc;
        EXPECT_TRUE(in_responses) << fc;
    }
}

// Mutates valid PDUs (byte flips, cuts, extensions) and checks the property on everything
// the decoders accept. Deterministic: a fixed seed.
TEST(RoundTrip, MutatedPdusThatDecodeReEncodeIdentically) {
    std::mt19937 rng(20240601);
    std::vector<ByteVec> seeds;
    for (const char* h : kValidRequests) seeds.push_back(hex(h));
    for (const char* h : kValidResponses) seeds.push_back(hex(h));
    std::size_t accepted_requests = 0;
    std::size_t accepted_responses = 0;
    std::uint8_t out[300];
    for (int iter = 0; iter < 300000; ++iter) {
        ByteVec pdu = seeds[rng() % seeds.size()];
        const int edits = 1 + static_cast<int>(rng() % 3);
        for (int e = 0; e < edits; ++e) {
            switch (rng() % 4) {
                case 0:
                    if (!pdu.empty()) pdu[rng() % pdu.size()] = static_cast<std::uint8_t>(rng());
                    break;
                case 1:
                    if (!pdu.empty()) pdu.resize(rng() % pdu.size());
                    break;
                case 2:
                    pdu.push_back(static_cast<std::uint8_t>(rng()));
                    break;
                default:
                    if (pdu.size() > 1) pdu[1 + rng() % (pdu.size() - 1)] ^= 1u << (rng() % 8);
                    break;
            }
        }
        Request rq;
        if (decode_request(view(pdu), rq).ok()) {
            ++accepted_requests;
            const EncodeResult enc = encode_request(rq, MutableBytes(out, sizeof out));
            ASSERT_TRUE(enc.ok()) << to_hex(view(pdu));
            ASSERT_EQ(to_hex(Bytes(out, enc.size)), to_hex(view(pdu)));
        }
        Response rs;
        if (decode_response(view(pdu), rs) == CodecError::Ok) {
            ++accepted_responses;
            const EncodeResult enc = encode_response(rs, MutableBytes(out, sizeof out));
            ASSERT_TRUE(enc.ok()) << to_hex(view(pdu));
            ASSERT_EQ(to_hex(Bytes(out, enc.size)), to_hex(view(pdu)));
        }
    }
    // The mutations must exercise the accept path, not only the reject paths.
    EXPECT_GT(accepted_requests, 10000u);
    EXPECT_GT(accepted_responses, 10000u);
}

// Everything a validated encode writes decodes back to the same fields.
TEST(RoundTrip, EncodeThenDecodeReadRequests) {
    std::uint8_t out[8];
    for (std::uint8_t fc : {0x01, 0x02, 0x03, 0x04}) {
        for (std::uint32_t q : {1u, 2u, 125u, 2000u}) {
            for (std::uint32_t a : {0u, 1u, 0xFF83u, 0xFFFFu}) {
                Request r;
                r.function = fc;
                r.address = static_cast<std::uint16_t>(a);
                r.quantity = static_cast<std::uint16_t>(q);
                const EncodeResult enc = encode_request(r, MutableBytes(out, sizeof out));
                Request back;
                const RequestStatus st = decode_request(Bytes(out, 5), back);
                if (enc.ok()) {
                    EXPECT_TRUE(st.ok());
                    EXPECT_EQ(back.address, a);
                    EXPECT_EQ(back.quantity, q);
                } else {
                    EXPECT_EQ(enc.error, CodecError::InvalidArgument);
                    // The out-of-spec bytes, written on purpose, are rejected the same way.
                    ASSERT_TRUE(encode_request(r, MutableBytes(out, sizeof out), true).ok());
                    EXPECT_FALSE(decode_request(Bytes(out, 5), back).ok());
                }
            }
        }
    }
}

}  // namespace
}  // namespace mbstorm::codec::test
