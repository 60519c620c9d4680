// HdrHistogram's percentile distribution text (.hgrm), exactly as HdrHistogram_c's
// hdr_percentiles_print writes it (and wrk2 prints), so existing plotters read it:
//
//        Value   Percentile   TotalCount 1/(1-Percentile)
//
//        0.105     0.000000            1         1.00
//        ...
//       12.345     1.000000        10000          inf
// #[Mean    =        1.234, StdDeviation   =        0.567]
// #[Max     =       12.345, Total count    =        10000]
// #[Buckets =           32, SubBuckets     =         2048]
//
// Values are the histogram's ns divided by value_unit_scaling_ratio (default 1e6: ms).
#pragma once

#include <cstdint>
#include <string>

#include "stats/histogram.hpp"

namespace mbstorm::report {

std::string format_hgrm(const stats::Histogram& histogram, double value_unit_scaling_ratio = 1e6,
                        std::uint32_t ticks_per_half_distance = 5);

}  // namespace mbstorm::report
