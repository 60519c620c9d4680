// The console report says what was asked of the target and, against the embedded slave, that
// the slave and the load share the machine's cores (issue #29, help that teaches).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "../support/run_mbstorm.hpp"

using mbstorm::test::run_mbstorm;
using testing::HasSubstr;

namespace {

TEST(RunHeader, SaysWhatWasRequestedAndThatTheEmbeddedSlaveSharesTheCores) {
    auto r =
        run_mbstorm("run -d 300ms -c 1 --depth 1 --fc 4 --addr 30011-30020 --quantity 2 -u 1", 60);
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_THAT(r.output, HasSubstr("note: request: 0x04 read_input_registers, addresses 10-19 "
                                    "sequential, quantity 2, unit 1"))
        << r.output;
    EXPECT_THAT(r.output, HasSubstr("cores with the load, so the numbers measure both"))
        << r.output;
}

}  // namespace
