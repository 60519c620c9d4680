#include "stats/hdr_encoding.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace mbstorm::stats {
namespace {

void expect_same_decoded_counts(const Histogram& a, const Histogram& b) {
    ASSERT_EQ(a.total_count(), b.total_count());
    const std::size_t n = std::max(a.counts_length(), b.counts_length());
    for (std::size_t i = 0; i < n; ++i) {
        const std::uint64_t ca = i < a.counts_length() ? a.count_at_index(i) : 0;
        const std::uint64_t cb = i < b.counts_length() ? b.count_at_index(i) : 0;
        ASSERT_EQ(ca, cb) << "index " << i;
    }
}

TEST(HdrEncoding, V2LayoutIsHdrHistograms) {
    Histogram h;
    h.record(1);
    h.record_n(3, 2);
    const std::vector<std::uint8_t> bytes = encode_hdr_v2(h);
    const std::vector<std::uint8_t> expected = {
        0x1c, 0x84, 0x93, 0x13,                          // V2 cookie, 8-byte words
        0x00, 0x00, 0x00, 0x04,                          // payload length
        0x00, 0x00, 0x00, 0x00,                          // normalizing index offset
        0x00, 0x00, 0x00, 0x03,                          // significant digits
        0,    0,    0,    0,    0,    0,    0,    1,     // lowest discernible value
        0x00, 0x00, 0x03, 0x46, 0x30, 0xb8, 0xa0, 0x00,  // highest trackable: 1 h in ns
        0x3f, 0xf0, 0,    0,    0,    0,    0,    0,     // integer-to-double ratio 1.0
        0x00, 0x02, 0x00, 0x04};  // counts 0,1,0,2 as ZigZag words (a lone zero is 0)
    EXPECT_EQ(bytes, expected);
}

TEST(HdrEncoding, ZeroRunsAreNegativeAndLargeCountsTakeSeveralBytes) {
    Histogram h;
    h.record_n(5, 300);  // index 5; indexes 0..4 are a run of five zeros
    const std::vector<std::uint8_t> bytes = encode_hdr_v2(h);
    ASSERT_EQ(bytes.size(), 40u + 3u);
    EXPECT_EQ(bytes[40], 0x09);  // -5 ZigZag = 9
    EXPECT_EQ(bytes[41], 0xd8);  // 300 ZigZag = 600 = 0x258: 0x58 | 0x80, then 0x04
    EXPECT_EQ(bytes[42], 0x04);
}

TEST(HdrEncoding, RoundTripKeepsEveryCount) {
    Histogram h;
    std::uint64_t v = 1;
    for (int i = 0; i < 2000; ++i) {
        h.record_n(v % 5'000'000'000ULL, 1 + static_cast<std::uint64_t>(i % 7));
        v = v * 6364136223846793005ULL + 1442695040888963407ULL;
    }
    h.record_n(1ULL << 40, 1ULL << 50);  // a count needing the 9-byte form's neighbours
    Histogram back(1000);
    const mbstorm::Error error =
        decode_hdr_compressed_base64(encode_hdr_compressed_base64(h), back);
    ASSERT_TRUE(error.ok()) << error.text();
    expect_same_decoded_counts(h, back);
    EXPECT_EQ(back.highest_trackable(), h.highest_trackable());
    // Decoded extremes are bucket edges, as in HdrHistogram; percentiles land in the same buckets.
    for (double p : {50.0, 90.0, 99.0, 99.9, 100.0})
        EXPECT_EQ(Histogram::lowest_equivalent(back.value_at_percentile(p)),
                  Histogram::lowest_equivalent(h.value_at_percentile(p)));
    back.narrow_extremes(h.min(), h.max());
    EXPECT_EQ(back.min(), h.min());
    EXPECT_EQ(back.max(), h.max());
}

TEST(HdrEncoding, EmptyHistogramRoundTrips) {
    Histogram h;
    Histogram back;
    back.record(7);
    ASSERT_TRUE(decode_hdr_compressed_base64(encode_hdr_compressed_base64(h), back).ok());
    EXPECT_TRUE(back.empty());
}

TEST(HdrEncoding, DecodesWhatHdrHistogramJavaWrote) {
    // Written by HdrHistogram 2.1.11 (Debian's libhdrhistogram-java): new Histogram(3600e9, 3),
    // recordValue(1), recordValue(3) twice, recordValueWithCount(5000, 300),
    // recordValue(123456789), encodeIntoCompressedByteBuffer, base64.
    const std::string java =
        "HISTFAAAACx4nJNpmSzMwMDAwwABzFCaEch0M9ixgMH+A1SEiYFlt/ENlvcvGZkAlu8IAg==";
    Histogram h;
    const mbstorm::Error error = decode_hdr_compressed_base64(java, h);
    ASSERT_TRUE(error.ok()) << error.text();
    Histogram expected;
    expected.record(1);
    expected.record_n(3, 2);
    expected.record_n(5000, 300);
    expected.record(123456789);
    expect_same_decoded_counts(h, expected);
    EXPECT_EQ(h.total_count(), 304u);
    EXPECT_EQ(h.max(), 123469823u);                 // Java's getMaxValue()
    EXPECT_EQ(h.value_at_percentile(99.0), 5003u);  // Java's getValueAtPercentile(99)
}

TEST(HdrEncoding, RefusesOtherSettingsAndDamage) {
    Histogram h;
    h.record(42);
    std::vector<std::uint8_t> bytes = encode_hdr_v2(h);
    Histogram out;
    mbstorm::Error error;

    std::vector<std::uint8_t> two_digits = bytes;
    two_digits[15] = 2;
    error = decode_hdr_v2(two_digits.data(), two_digits.size(), out);
    EXPECT_EQ(error.code(), mbstorm::ErrorCode::InvalidInput);
    EXPECT_NE(error.message().find("histogram settings differ: 2 significant digits"),
              std::string::npos)
        << error.text();

    std::vector<std::uint8_t> coarse = bytes;
    coarse[23] = 100;  // lowest discernible value 100
    error = decode_hdr_v2(coarse.data(), coarse.size(), out);
    EXPECT_EQ(error.code(), mbstorm::ErrorCode::InvalidInput);
    EXPECT_NE(error.message().find("lowest discernible value 100"), std::string::npos)
        << error.text();

    error = decode_hdr_v2(bytes.data(), bytes.size() - 1, out);
    EXPECT_EQ(error.code(), mbstorm::ErrorCode::InvalidInput);
    EXPECT_NE(error.message().find("truncated"), std::string::npos) << error.text();

    std::vector<std::uint8_t> huge_run = bytes;
    huge_run.resize(40);
    huge_run[7] = 9;
    for (int i = 0; i < 8; ++i) huge_run.push_back(0xff);
    huge_run.push_back(0xff);  // ZigZag of INT64_MIN-ish: a run no histogram has
    error = decode_hdr_v2(huge_run.data(), huge_run.size(), out);
    EXPECT_EQ(error.code(), mbstorm::ErrorCode::InvalidInput);
    EXPECT_NE(error.message().find("past its highest trackable value"), std::string::npos)
        << error.text();

    error = decode_hdr_compressed_base64("HISTFAAA!!!!", out);
    EXPECT_EQ(error.code(), mbstorm::ErrorCode::InvalidInput);
    EXPECT_EQ(error.message(), "histogram is not valid base64");
    error = decode_hdr_compressed_base64("AAAAAAAAAAAA", out);
    EXPECT_EQ(error.code(), mbstorm::ErrorCode::InvalidInput);
    EXPECT_EQ(error.message(), "not a compressed HdrHistogram V2 encoding");
    // A valid wrapper around bytes that are not zlib.
    const std::uint8_t fake[] = {0x1c, 0x84, 0x93, 0x14, 0, 0, 0, 4, 1, 2, 3, 4};
    error = decode_hdr_compressed_base64(base64_encode(fake, sizeof fake), out);
    EXPECT_EQ(error.code(), mbstorm::ErrorCode::InvalidInput);
    EXPECT_EQ(error.message(), "compressed histogram is corrupt");
}

TEST(Base64, MatchesTheStandardAlphabetAndPadding) {
    const std::uint8_t data[] = {'f', 'o', 'o', 'b', 'a', 'r'};
    EXPECT_EQ(base64_encode(data, 0), "");
    EXPECT_EQ(base64_encode(data, 1), "Zg==");
    EXPECT_EQ(base64_encode(data, 2), "Zm8=");
    EXPECT_EQ(base64_encode(data, 6), "Zm9vYmFy");
    std::vector<std::uint8_t> out;
    ASSERT_TRUE(base64_decode("Zm9vYg==", out));
    EXPECT_EQ(std::string(out.begin(), out.end()), "foob");
    EXPECT_FALSE(base64_decode("Zm9", out));
    EXPECT_FALSE(base64_decode("Z=9v", out));
    EXPECT_FALSE(base64_decode("Zg==Zg==", out));
}

}  // namespace
}  // namespace mbstorm::stats
