#include <gtest/gtest.h>

#include "server/stats.hpp"

namespace mbstorm::server {
namespace {

// Fault injection answers with any exception code 1..255 (--exception-code): each is counted
// under its own code. Codes above 15 were folded onto code & 15 before.
TEST(ServerCounters, EveryExceptionCodeIsCountedUnderItself) {
    ServerCounters counters;
    counters.add_exception(0x13);
    counters.add_exception(0xFF);
    counters.add_exception(0x02);
    const ServerStats s = counters.snapshot();
    EXPECT_EQ(s.exceptions[0x13], 1u);
    EXPECT_EQ(s.exceptions[0xFF], 1u);
    EXPECT_EQ(s.exceptions[0x02], 1u);
    EXPECT_EQ(s.exceptions[0x03], 0u);
    EXPECT_EQ(s.exceptions[0x0F], 0u);
    EXPECT_EQ(s.exceptions_total(), 3u);
}

}  // namespace
}  // namespace mbstorm::server
