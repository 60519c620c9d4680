// libFuzzer harness: an HdrHistogram .hlog log (what `merge` reads from every shard): parsed,
// or refused with a reason. Every histogram it accepts, encoded again and read back, is the
// same histogram: the same total, min and max, the same count at every counts index, and the
// same value at each of a spread of percentiles (what merge and the reports print).
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>

#include "report/hlog.hpp"
#include "stats/hdr_encoding.hpp"

namespace {

using mbstorm::stats::Histogram;

void check(bool ok) {
    if (!ok) std::abort();
}

void same_histogram(const Histogram& a, const Histogram& b) {
    check(a.total_count() == b.total_count() && a.min() == b.min() && a.max() == b.max());
    // Counts past the shorter array must be zero: the encoding stops at the last non-zero.
    const std::size_t n = std::max(a.counts_length(), b.counts_length());
    for (std::size_t i = 0; i < n; ++i) {
        const std::uint64_t ca = i < a.counts_length() ? a.count_at_index(i) : 0;
        const std::uint64_t cb = i < b.counts_length() ? b.count_at_index(i) : 0;
        check(ca == cb);
    }
    for (const double p : {0.0, 1.0, 25.0, 50.0, 75.0, 90.0, 99.0, 99.9, 99.99, 100.0})
        check(a.value_at_percentile(p) == b.value_at_percentile(p));
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string_view text(reinterpret_cast<const char*>(data), size);
    const mbstorm::Result<mbstorm::report::Hlog> log = mbstorm::report::parse_hlog(text);
    if (!log.ok()) {
        check(!log.error().message().empty());  // a refusal always says why
        return 0;
    }
    for (const auto& interval : log->intervals) {
        Histogram again;
        check(mbstorm::stats::decode_hdr_compressed_base64(
                  mbstorm::stats::encode_hdr_compressed_base64(interval.histogram), again)
                  .ok());
        same_histogram(interval.histogram, again);
    }
    return 0;
}
