#include "stats/hdr_encoding.hpp"

#include <zlib.h>

#include <array>
#include <bit>
#include <cstring>
#include <limits>
#include <new>

namespace mbstorm::stats {
namespace {

// Both cookies carry the word size (0x10: 8-byte counts) in bits 4..7; readers mask it off.
constexpr std::uint32_t kWordSizeBits = 0x10;
constexpr std::uint32_t kCookieBaseMask = ~std::uint32_t{0xf0};
constexpr std::size_t kV2HeaderSize = 40;
// A word is ZigZag LEB128 in at most 9 bytes: 8 of 7 bits, then one of the top 8 bits.
constexpr int kSevenBitBytes = 8;
// Largest payload a histogram we can hold may need (every count a full word); more is refused
// rather than inflated without bound.
constexpr std::size_t kMaxPayloadBytes = 1u << 20;

Error bad_histogram(std::string message) {
    return Error(ErrorCode::InvalidInput, std::move(message));
}

void put_u32(std::vector<std::uint8_t>& out, std::uint32_t v) {
    for (int shift = 24; shift >= 0; shift -= 8)
        out.push_back(static_cast<std::uint8_t>(v >> shift));
}
void put_u64(std::vector<std::uint8_t>& out, std::uint64_t v) {
    for (int shift = 56; shift >= 0; shift -= 8)
        out.push_back(static_cast<std::uint8_t>(v >> shift));
}
void set_u32(std::vector<std::uint8_t>& out, std::size_t at, std::uint32_t v) {
    for (int i = 0; i < 4; ++i) out[at + i] = static_cast<std::uint8_t>(v >> (24 - 8 * i));
}
std::uint32_t get_u32(const std::uint8_t* p) {
    return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) |
           std::uint32_t{p[3]};
}
std::uint64_t get_u64(const std::uint8_t* p) {
    return (std::uint64_t{get_u32(p)} << 32) | get_u32(p + 4);
}

void put_word(std::vector<std::uint8_t>& out, std::int64_t value) {
    const std::uint64_t zz =
        (static_cast<std::uint64_t>(value) << 1) ^ static_cast<std::uint64_t>(value >> 63);
    for (int i = 0; i < kSevenBitBytes; ++i) {
        const std::uint64_t rest = zz >> (7 * (i + 1));
        const auto low7 = static_cast<std::uint8_t>((zz >> (7 * i)) & 0x7f);
        if (rest == 0) {
            out.push_back(low7);
            return;
        }
        // one-place: LEB128's continuation bit, not Modbus's exception bit
        out.push_back(static_cast<std::uint8_t>(low7 | 0x80));
    }
    out.push_back(static_cast<std::uint8_t>(zz >> 56));
}

// Reads one word at p (end excluded); returns the bytes used, 0 when the data ends mid-word.
std::size_t get_word(const std::uint8_t* p, const std::uint8_t* end, std::int64_t& value) {
    std::uint64_t zz = 0;
    std::size_t used = 0;
    for (int i = 0; i < kSevenBitBytes; ++i) {
        if (p + used >= end) return 0;
        const std::uint8_t b = p[used++];
        zz |= std::uint64_t{b & 0x7fu} << (7 * i);
        if ((b & 0x80) == 0) {
            value = static_cast<std::int64_t>((zz >> 1) ^ (~(zz & 1) + 1));
            return used;
        }
    }
    if (p + used >= end) return 0;
    zz |= std::uint64_t{p[used++]} << 56;
    value = static_cast<std::int64_t>((zz >> 1) ^ (~(zz & 1) + 1));
    return used;
}

constexpr std::string_view kAlphabet =
    "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

}  // namespace

std::vector<std::uint8_t> encode_hdr_v2(const Histogram& histogram) {
    std::size_t relevant = 0;
    for (std::size_t i = histogram.counts_length(); i > 0; --i) {
        if (histogram.count_at_index(i - 1) != 0) {
            relevant = i;
            break;
        }
    }
    std::vector<std::uint8_t> out;
    out.reserve(kV2HeaderSize + 64);
    put_u32(out, kHdrV2EncodingCookie | kWordSizeBits);
    put_u32(out, 0);  // payload length, set below
    put_u32(out, 0);  // normalizing index offset: ours never shifts
    put_u32(out, static_cast<std::uint32_t>(Histogram::kSignificantDigits));
    put_u64(out, 1);  // lowest discernible value (ns)
    put_u64(out, histogram.highest_trackable());
    put_u64(out, std::bit_cast<std::uint64_t>(1.0));  // integer-to-double ratio
    for (std::size_t i = 0; i < relevant;) {
        const std::uint64_t count = histogram.count_at_index(i);
        if (count != 0) {
            put_word(out, static_cast<std::int64_t>(count));
            ++i;
            continue;
        }
        std::size_t zeros = 1;
        while (i + zeros < relevant && histogram.count_at_index(i + zeros) == 0) ++zeros;
        // A single zero is written as 0; a run as minus its length.
        put_word(out, zeros == 1 ? 0 : -static_cast<std::int64_t>(zeros));
        i += zeros;
    }
    set_u32(out, 4, static_cast<std::uint32_t>(out.size() - kV2HeaderSize));
    return out;
}

std::string encode_hdr_compressed_base64(const Histogram& histogram) {
    const std::vector<std::uint8_t> plain = encode_hdr_v2(histogram);
    uLongf bound = compressBound(static_cast<uLong>(plain.size()));
    std::vector<std::uint8_t> out(8 + bound);
    // compress2 writes the zlib wrapper HdrHistogram's readers inflate.
    // With compressBound's room the only failure is zlib's own allocation.
    if (compress2(out.data() + 8, &bound, plain.data(), static_cast<uLong>(plain.size()),
                  Z_BEST_COMPRESSION) != Z_OK)
        throw std::bad_alloc();
    out.resize(8 + bound);
    set_u32(out, 0, kHdrV2CompressedCookie | kWordSizeBits);
    set_u32(out, 4, static_cast<std::uint32_t>(bound));
    return base64_encode(out.data(), out.size());
}

Error decode_hdr_v2(const std::uint8_t* data, std::size_t size, Histogram& out) {
    if (size < kV2HeaderSize) {
        return bad_histogram("histogram encoding shorter than its header");
    }
    const std::uint32_t cookie = get_u32(data);
    if ((cookie & kCookieBaseMask) != kHdrV2EncodingCookie) {
        return bad_histogram("not an HdrHistogram V2 encoding (cookie " + std::to_string(cookie) +
                             ")");
    }
    const std::uint32_t payload = get_u32(data + 4);
    const std::uint32_t normalizing_offset = get_u32(data + 8);
    const std::uint32_t digits = get_u32(data + 12);
    const std::uint64_t lowest = get_u64(data + 16);
    const std::uint64_t highest = get_u64(data + 24);
    const double ratio = std::bit_cast<double>(get_u64(data + 32));
    if (payload > size - kV2HeaderSize) {
        return bad_histogram("histogram encoding truncated (payload longer than the data)");
    }
    if (digits != static_cast<std::uint32_t>(Histogram::kSignificantDigits) || lowest != 1 ||
        normalizing_offset != 0 || ratio != 1.0) {
        return bad_histogram(
            "histogram settings differ: " + std::to_string(digits) +
            " significant digits, lowest discernible value " + std::to_string(lowest) +
            (normalizing_offset != 0 ? ", shifted counts" : "") +
            (ratio != 1.0 ? ", a double histogram" : "") +
            " (mbstorm records 3 significant digits, lowest 1 ns, integer values)");
    }
    if (highest < 2 || highest > (std::uint64_t{1} << 62)) {
        return bad_histogram("histogram highest trackable value " + std::to_string(highest) +
                             " out of range");
    }
    Histogram decoded(highest);
    const std::uint8_t* p = data + kV2HeaderSize;
    const std::uint8_t* end = p + payload;
    std::size_t index = 0;
    while (p < end) {
        std::int64_t word = 0;
        const std::size_t used = get_word(p, end, word);
        if (used == 0) {
            return bad_histogram("histogram counts truncated mid-word");
        }
        p += used;
        if (word < 0) {
            const std::uint64_t zeros = static_cast<std::uint64_t>(-(word + 1)) + 1;
            if (zeros > decoded.counts_length() - index) {
                return bad_histogram("histogram counts run past its highest trackable value");
            }
            index += static_cast<std::size_t>(zeros);
            continue;
        }
        if (index >= decoded.counts_length()) {
            return bad_histogram("histogram counts run past its highest trackable value");
        }
        decoded.add_at_index(index++, static_cast<std::uint64_t>(word));
    }
    out = std::move(decoded);
    return Error::none();
}

Error decode_hdr_compressed_base64(std::string_view text, Histogram& out) {
    std::vector<std::uint8_t> raw;
    if (!base64_decode(text, raw)) {
        return bad_histogram("histogram is not valid base64");
    }
    if (raw.size() < 8 || (get_u32(raw.data()) & kCookieBaseMask) != kHdrV2CompressedCookie) {
        return bad_histogram("not a compressed HdrHistogram V2 encoding");
    }
    const std::uint32_t compressed = get_u32(raw.data() + 4);
    if (compressed > raw.size() - 8) {
        return bad_histogram("compressed histogram truncated");
    }
    z_stream zs{};
    if (inflateInit(&zs) != Z_OK) {
        return Error(ErrorCode::Io, "zlib could not start");
    }
    std::vector<std::uint8_t> plain(kV2HeaderSize + 4096);
    zs.next_in = raw.data() + 8;
    zs.avail_in = compressed;
    std::size_t produced = 0;
    int rc = Z_OK;
    while (rc == Z_OK) {
        if (produced == plain.size()) {
            if (plain.size() >= kMaxPayloadBytes) break;
            plain.resize(plain.size() * 2);
        }
        zs.next_out = plain.data() + produced;
        zs.avail_out = static_cast<uInt>(plain.size() - produced);
        rc = inflate(&zs, Z_NO_FLUSH);
        produced = plain.size() - zs.avail_out;
    }
    inflateEnd(&zs);
    if (rc != Z_STREAM_END) {
        return bad_histogram(rc == Z_OK ? "compressed histogram too large"
                                        : "compressed histogram is corrupt");
    }
    return decode_hdr_v2(plain.data(), produced, out);
}

std::string base64_encode(const std::uint8_t* data, std::size_t size) {
    std::string out;
    out.reserve((size + 2) / 3 * 4);
    for (std::size_t i = 0; i < size; i += 3) {
        const std::size_t n = std::min<std::size_t>(3, size - i);
        std::uint32_t group = std::uint32_t{data[i]} << 16;
        if (n > 1) group |= std::uint32_t{data[i + 1]} << 8;
        if (n > 2) group |= data[i + 2];
        for (std::size_t k = 0; k < 4; ++k)
            out.push_back(k <= n ? kAlphabet[(group >> (18 - 6 * k)) & 0x3f] : '=');
    }
    return out;
}

bool base64_decode(std::string_view text, std::vector<std::uint8_t>& out) {
    out.clear();
    if (text.size() % 4 != 0) return false;
    out.reserve(text.size() / 4 * 3);
    for (std::size_t i = 0; i < text.size(); i += 4) {
        std::uint32_t group = 0;
        int padding = 0;
        for (std::size_t k = 0; k < 4; ++k) {
            const char c = text[i + k];
            std::uint32_t v = 0;
            if (c == '=') {
                // Padding only at the very end, at most two.
                if (i + 4 != text.size() || k < 2) return false;
                ++padding;
            } else {
                if (padding != 0) return false;
                const auto at = kAlphabet.find(c);
                if (at == std::string_view::npos) return false;
                v = static_cast<std::uint32_t>(at);
            }
            group = (group << 6) | v;
        }
        out.push_back(static_cast<std::uint8_t>(group >> 16));
        if (padding < 2) out.push_back(static_cast<std::uint8_t>(group >> 8));
        if (padding < 1) out.push_back(static_cast<std::uint8_t>(group));
    }
    return true;
}

}  // namespace mbstorm::stats
