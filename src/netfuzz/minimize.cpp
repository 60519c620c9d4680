#include "netfuzz/minimize.hpp"

#include <algorithm>

#include "codec/bytes.hpp"
#include "codec/limits.hpp"
#include "codec/mbap.hpp"

namespace mbstorm::netfuzz {

Case split_frames(const Case& c) {
    Case out = c;
    out.steps.clear();
    for (const Step& s : c.steps) {
        if (s.op != Op::Send || s.bytes.size() < codec::limits::kMbapHeader) {
            out.steps.push_back(s);
            continue;
        }
        std::size_t off = 0;
        std::vector<Step> parts;
        while (s.bytes.size() - off >= codec::limits::kMbapHeader) {
            const std::size_t size = codec::announced_adu_size(s.bytes.data() + off);
            if (size > s.bytes.size() - off || size <= 6u) break;
            parts.push_back(Step{Op::Send,
                                 s.conn,
                                 parts.empty() ? s.delay_us : 0u,
                                 0,
                                 {s.bytes.begin() + static_cast<std::ptrdiff_t>(off),
                                  s.bytes.begin() + static_cast<std::ptrdiff_t>(off + size)}});
            off += size;
        }
        if (off != s.bytes.size() || parts.size() < 2) {
            out.steps.push_back(s);  // not a clean run of frames: keep as is
        } else {
            out.steps.insert(out.steps.end(), parts.begin(), parts.end());
        }
    }
    return out;
}

namespace {

using Reproduces = std::function<bool(const Case&)>;

// ddmin over the steps: drop chunks while the oracle still fires.
void drop_steps(Case& best, const Reproduces& reproduces, unsigned& budget) {
    std::size_t n = 2;
    while (best.steps.size() >= 2 && budget > 0) {
        const std::size_t len = best.steps.size();
        const std::size_t chunk = (len + n - 1) / n;
        bool reduced = false;
        // Try removing each chunk (testing complements, the ddmin step that shrinks fastest).
        for (std::size_t start = 0; start < len && budget > 0; start += chunk) {
            Case candidate = best;
            candidate.steps.erase(candidate.steps.begin() + static_cast<std::ptrdiff_t>(start),
                                  candidate.steps.begin() +
                                      static_cast<std::ptrdiff_t>(std::min(len, start + chunk)));
            if (candidate.steps.empty()) continue;
            --budget;
            if (reproduces(candidate)) {
                best = std::move(candidate);
                n = std::max<std::size_t>(n - 1, 2);
                reduced = true;
                break;
            }
        }
        if (!reduced) {
            if (n >= len) break;
            n = std::min(len, n * 2);
        }
    }
}

bool is_one_frame(const std::vector<std::uint8_t>& bytes) {
    return bytes.size() > codec::limits::kMbapHeader &&
           bytes.size() == codec::announced_adu_size(bytes.data());
}

// The frame with its PDU cut to `pdu_size` bytes and its MBAP length field to match.
std::vector<std::uint8_t> cut_frame(const std::vector<std::uint8_t>& frame, std::size_t pdu_size) {
    std::vector<std::uint8_t> out(
        frame.begin(),
        frame.begin() + static_cast<std::ptrdiff_t>(codec::limits::kMbapHeader + pdu_size));
    codec::store_be16(out.data() + 4, static_cast<std::uint16_t>(1 + pdu_size));
    return out;
}

// Byte level: the shortest tail of each well-framed send's PDU that still makes the oracle
// fire, found by bisection (each candidate stays a well-framed ADU, so it still pipelines).
void shorten_frames(Case& best, const Reproduces& reproduces, unsigned& budget) {
    for (std::size_t i = 0; i < best.steps.size() && budget > 0; ++i) {
        if (best.steps[i].op != Op::Send || !is_one_frame(best.steps[i].bytes)) continue;
        std::size_t keep = best.steps[i].bytes.size() - codec::limits::kMbapHeader;
        std::size_t shortest = 1;  // the function code stays
        while (shortest < keep && budget > 0) {
            const std::size_t size = shortest + (keep - shortest) / 2;
            Case candidate = best;
            candidate.steps[i].bytes = cut_frame(best.steps[i].bytes, size);
            --budget;
            if (reproduces(candidate)) {
                best = std::move(candidate);
                keep = size;
            } else {
                shortest = size + 1;
            }
        }
    }
}

}  // namespace

Case minimize_case(const Case& original, const Reproduces& reproduces, unsigned budget,
                   bool byte_level) {
    Case best = split_frames(original);
    if (best.steps.size() != original.steps.size()) {
        if (budget > 0 && reproduces(best)) {
            --budget;
        } else {
            if (budget > 0) --budget;
            best = original;
        }
    }
    drop_steps(best, reproduces, budget);
    if (byte_level) shorten_frames(best, reproduces, budget);
    return best;
}

}  // namespace mbstorm::netfuzz
