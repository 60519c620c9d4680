#include "report/hgrm.hpp"

#include <cinttypes>
#include <cstdio>

namespace mbstorm::report {
namespace {

// printf, not fmt: the layout must match HdrHistogram_c's byte for byte (including "inf").
template <typename... Args>
void append_printf(std::string& out, const char* format, Args... args) {
    char line[256];
    const int n = std::snprintf(line, sizeof line, format, args...);
    if (n > 0) out.append(line, static_cast<std::size_t>(n) < sizeof line ? n : sizeof line - 1);
}

}  // namespace

std::string format_hgrm(const stats::Histogram& histogram, double value_unit_scaling_ratio,
                        std::uint32_t ticks_per_half_distance) {
    const double scale = value_unit_scaling_ratio > 0.0 ? value_unit_scaling_ratio : 1.0;
    std::string out;
    append_printf(out, "%12s %12s %12s %12s\n\n", "Value", "Percentile", "TotalCount",
                  "1/(1-Percentile)");
    stats::PercentileIterator it(histogram, ticks_per_half_distance);
    stats::PercentilePoint point;
    while (it.next(point)) {
        const double fraction = point.percentile / 100.0;
        append_printf(out, "%12.3f %12f %12" PRIu64 " %12.2f\n",
                      static_cast<double>(point.value) / scale, fraction, point.total_count,
                      1.0 / (1.0 - fraction));
    }
    // The exact max, not its bucket's upper edge: no row or footer exceeds what was recorded.
    const std::uint64_t max = histogram.max();
    append_printf(out, "#[Mean    = %12.3f, StdDeviation   = %12.3f]\n", histogram.mean() / scale,
                  histogram.stddev() / scale);
    append_printf(out, "#[Max     = %12.3f, Total count    = %12" PRIu64 "]\n",
                  static_cast<double>(max) / scale, histogram.total_count());
    append_printf(out, "#[Buckets = %12d, SubBuckets     = %12d]\n",
                  static_cast<int>(histogram.bucket_count()),
                  static_cast<int>(stats::Histogram::kSubBucketCount));
    return out;
}

}  // namespace mbstorm::report
