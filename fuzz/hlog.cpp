// libFuzzer harness: an HdrHistogram .hlog log (what `merge` reads from every shard): parsed,
// or refused with a reason; the histograms it accepts answer percentile queries.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>

#include "report/hlog.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string_view text(reinterpret_cast<const char*>(data), size);
    mbstorm::report::Hlog log;
    std::string error;
    if (!mbstorm::report::parse_hlog(text, log, error) && error.empty()) std::abort();
    return 0;
}
