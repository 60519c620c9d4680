// libFuzzer harness: an HdrHistogram .hlog log (what `merge` reads from every shard): parsed,
// or refused with a reason. Every histogram it accepts, encoded again and read back, has the
// same counts (total, and the value at each percentile).
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>

#include "report/hlog.hpp"
#include "stats/hdr_encoding.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string_view text(reinterpret_cast<const char*>(data), size);
    mbstorm::report::Hlog log;
    std::string error;
    if (!mbstorm::report::parse_hlog(text, log, error)) {
        if (error.empty()) std::abort();  // a refusal always says why
        return 0;
    }
    for (const auto& interval : log.intervals) {
        const mbstorm::stats::Histogram& h = interval.histogram;
        mbstorm::stats::Histogram again;
        if (!mbstorm::stats::decode_hdr_compressed_base64(
                mbstorm::stats::encode_hdr_compressed_base64(h), again, error))
            std::abort();
        if (again.total_count() != h.total_count() || again.max() != h.max() ||
            again.min() != h.min())
            std::abort();
    }
    return 0;
}
