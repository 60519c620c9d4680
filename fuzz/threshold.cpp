// libFuzzer harness: one threshold expression ("p99 < 20ms", "errors == 0", "read.p50 <= 1s").
// Accepted or refused with a reason; never undefined behaviour.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>

#include "scenario/threshold.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string_view text(reinterpret_cast<const char*>(data), size);
    mbstorm::scenario::ThresholdSpec spec;
    std::string error;
    const bool ok = mbstorm::scenario::parse_threshold(text, spec, error);
    if (!ok && error.empty()) std::abort();  // a refusal always says why
    return 0;
}
