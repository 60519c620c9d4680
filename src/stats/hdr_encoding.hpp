// HdrHistogram's portable histogram encoding, as its interval logs carry it: the "V2"
// layout (big-endian header, then counts as ZigZag LEB128 words with runs of zeros written as
// one negative word), deflated by zlib behind a second header, then base64.
//
// Our Histogram has HdrHistogram's layout for lowest discernible value 1 and 3 significant
// digits (2048 sub-buckets, same counts index for every value), so counts map index for index
// and a decoded histogram is the one encoded. Histograms with other settings are refused when
// decoded: their buckets do not line up with ours, and merging them would not be exact.
//
// Not for the hot path: encoding and decoding allocate.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "stats/histogram.hpp"
#include "util/error.hpp"

namespace mbstorm::stats {

inline constexpr std::uint32_t kHdrV2EncodingCookie = 0x1c849303;
inline constexpr std::uint32_t kHdrV2CompressedCookie = 0x1c849304;

// The V2 encoding (uncompressed), counts up to the highest non-zero one.
std::vector<std::uint8_t> encode_hdr_v2(const Histogram& histogram);
// The compressed wrapper around encode_hdr_v2, base64: the last field of a log line.
std::string encode_hdr_compressed_base64(const Histogram& histogram);

// Decodes into out (replaced; a caller reading a long log reuses one histogram). On failure,
// an InvalidInput error (e.g. "histogram is not valid base64", "histogram settings differ: 2
// significant digits, lowest 1000 (mbstorm: 3 digits, lowest 1 ns)") and out unchanged.
Error decode_hdr_v2(const std::uint8_t* data, std::size_t size, Histogram& out);
Error decode_hdr_compressed_base64(std::string_view text, Histogram& out);

std::string base64_encode(const std::uint8_t* data, std::size_t size);
// False on a character outside the standard alphabet or a bad length or padding.
bool base64_decode(std::string_view text, std::vector<std::uint8_t>& out);

}  // namespace mbstorm::stats
