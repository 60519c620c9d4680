#include "netfuzz/minimize.hpp"

#include <algorithm>

#include "codec/bytes.hpp"
#include "codec/limits.hpp"

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
            const std::size_t size = 6u + codec::load_be16(s.bytes.data() + off + 4);
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

Case minimize_case(const Case& original, const std::function<bool(const Case&)>& reproduces,
                   unsigned budget) {
    Case best = split_frames(original);
    if (best.steps.size() < 2) return original;
    if (best.steps.size() != original.steps.size()) {
        if (budget == 0 || !reproduces(best)) return original;
        --budget;
    }
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
    return best;
}

}  // namespace mbstorm::netfuzz
