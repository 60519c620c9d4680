#include "netfuzz/minimize.hpp"

#include <algorithm>

#include "codec/bytes.hpp"
#include "codec/limits.hpp"
#include "codec/mbap.hpp"
#include "netfuzz/wire.hpp"

namespace mbstorm::netfuzz {

namespace {

// The whole frame at the start of `bytes` in `framing`, if one is there and a conforming reader
// takes it (not a frame broken on purpose): its size, else 0.
std::size_t whole_frame_at(codec::Bytes bytes, codec::Framing framing) {
    if (framing == codec::Framing::Mbap) {
        if (bytes.size() < codec::limits::kMbapHeader) return 0;
        const std::size_t size = codec::announced_adu_size(bytes.data());
        return size > 6u && size <= bytes.size() ? size : 0;
    }
    WireFrame w;
    if (cut_frame(bytes, framing, true, 0, w) != WireCut::Frame || !w.discard.empty()) return 0;
    return w.size;
}

}  // namespace

Case split_frames(const Case& c, codec::Framing framing) {
    Case out = c;
    out.steps.clear();
    for (const Step& s : c.steps) {
        if (s.op != Op::Send) {
            out.steps.push_back(s);
            continue;
        }
        std::size_t off = 0;
        std::vector<Step> parts;
        while (off < s.bytes.size()) {
            const std::size_t size = whole_frame_at(codec::Bytes(s.bytes).subspan(off), framing);
            if (size == 0) break;
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

bool is_one_frame(const std::vector<std::uint8_t>& bytes, codec::Framing framing) {
    return !bytes.empty() && whole_frame_at(bytes, framing) == bytes.size();
}

// The frame with its PDU cut to `pdu_size` bytes, its length field (MBAP) or its CRC / LRC
// (RTU, ASCII) made to match.
std::vector<std::uint8_t> with_pdu_cut(const std::vector<std::uint8_t>& frame, std::size_t pdu_size,
                                       codec::Framing framing) {
    std::vector<std::uint8_t> mbap = frame;
    if (framing != codec::Framing::Mbap) {
        WireFrame w;
        (void)cut_frame(frame, framing, true, 0, w);  // whole: is_one_frame said so
        mbap = std::move(w.mbap);
    }
    mbap.resize(codec::limits::kMbapHeader + pdu_size);
    codec::store_be16(mbap.data() + 4, static_cast<std::uint16_t>(1 + pdu_size));
    return framing == codec::Framing::Mbap ? mbap : reframe(mbap, framing);
}

// The PDU's size in a whole frame.
std::size_t pdu_size_of(const std::vector<std::uint8_t>& frame, codec::Framing framing) {
    if (framing == codec::Framing::Mbap) return frame.size() - codec::limits::kMbapHeader;
    WireFrame w;
    (void)cut_frame(frame, framing, true, 0, w);
    return w.mbap.size() - codec::limits::kMbapHeader;
}

// Byte level: the shortest tail of each well-framed send's PDU that still makes the oracle
// fire, found by bisection (each candidate stays a well-framed ADU, so it still pipelines).
void shorten_frames(Case& best, const Reproduces& reproduces, unsigned& budget,
                    codec::Framing framing) {
    for (std::size_t i = 0; i < best.steps.size() && budget > 0; ++i) {
        if (best.steps[i].op != Op::Send || !is_one_frame(best.steps[i].bytes, framing)) continue;
        std::size_t keep = pdu_size_of(best.steps[i].bytes, framing);
        std::size_t shortest = 1;  // the function code stays
        while (shortest < keep && budget > 0) {
            const std::size_t size = shortest + (keep - shortest) / 2;
            Case candidate = best;
            candidate.steps[i].bytes = with_pdu_cut(best.steps[i].bytes, size, framing);
            // An RTU reader that infers the length from the function code would wait for the
            // rest of this one: it is not a shorter frame, and not worth a run.
            const bool whole = is_one_frame(candidate.steps[i].bytes, framing);
            if (whole) --budget;
            if (whole && reproduces(candidate)) {
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
                   bool byte_level, codec::Framing framing) {
    Case best = split_frames(original, framing);
    if (best.steps.size() != original.steps.size()) {
        if (budget > 0 && reproduces(best)) {
            --budget;
        } else {
            if (budget > 0) --budget;
            best = original;
        }
    }
    drop_steps(best, reproduces, budget);
    if (byte_level) shorten_frames(best, reproduces, budget, framing);
    return best;
}

}  // namespace mbstorm::netfuzz
