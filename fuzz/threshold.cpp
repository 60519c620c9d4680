// libFuzzer harness: one threshold expression ("p99 < 20ms", "errors == 0", "read.p50 <= 1s").
// Accepted or refused with a reason; never undefined behaviour. An accepted expression's
// normalised text (what reports print and `merge` reads back) parses to the same threshold,
// field by field, and its limit is a number (never NaN).
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>

#include "scenario/threshold.hpp"

namespace {

using mbstorm::scenario::ThresholdSpec;

bool same(const ThresholdSpec& a, const ThresholdSpec& b) {
    return a.text == b.text && a.operation == b.operation && a.metric == b.metric &&
           a.percentile == b.percentile && a.exception_code == b.exception_code &&
           a.comparison == b.comparison && a.limit == b.limit;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string_view text(reinterpret_cast<const char*>(data), size);
    const auto spec = mbstorm::scenario::parse_threshold(text);
    if (!spec.ok()) {
        if (spec.error().message().empty()) std::abort();  // a refusal always says why
        return 0;
    }
    if (std::isnan(spec->limit) || std::isnan(spec->percentile)) std::abort();
    const auto again = mbstorm::scenario::parse_threshold(spec->text);
    if (!again.ok() || !same(*spec, *again)) std::abort();
    return 0;
}
