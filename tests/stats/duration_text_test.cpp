// Durations on command lines and in YAML: one parser for every flag and key.
#include "stats/duration_text.hpp"

#include <gtest/gtest.h>

namespace {

using mbstorm::stats::parse_duration_ns;

std::uint64_t ns_of(const char* text, std::uint64_t unit = 1'000'000'000ULL) {
    std::uint64_t ns = 12345;
    EXPECT_TRUE(parse_duration_ns(text, ns, unit)) << text;
    return ns;
}

bool rejects(const char* text) {
    std::uint64_t ns = 0;
    return !parse_duration_ns(text, ns);
}

TEST(DurationText, SingleUnits) {
    EXPECT_EQ(ns_of("500ms"), 500'000'000u);
    EXPECT_EQ(ns_of("1.5s"), 1'500'000'000u);
    EXPECT_EQ(ns_of("250us"), 250'000u);
    EXPECT_EQ(ns_of("250\xC2\xB5s"), 250'000u);
    EXPECT_EQ(ns_of("2m"), 120'000'000'000u);
    EXPECT_EQ(ns_of("2min"), 120'000'000'000u);
    EXPECT_EQ(ns_of("1h"), 3'600'000'000'000u);
    EXPECT_EQ(ns_of("7ns"), 7u);
}

TEST(DurationText, CompoundForms) {
    EXPECT_EQ(ns_of("1m30s"), 90'000'000'000u);
    EXPECT_EQ(ns_of("1h2m"), 3'720'000'000'000u);
    EXPECT_EQ(ns_of("1s500ms"), 1'500'000'000u);
    EXPECT_EQ(ns_of("1h 2m 3s"), 3'723'000'000'000u);
}

TEST(DurationText, BareNumberTakesTheDefaultUnit) {
    EXPECT_EQ(ns_of("3"), 3'000'000'000u);
    EXPECT_EQ(ns_of("2.5", 1'000'000u), 2'500'000u);
}

TEST(DurationText, RejectsWhatIsNotADuration) {
    EXPECT_TRUE(rejects(""));
    EXPECT_TRUE(rejects("nan"));
    EXPECT_TRUE(rejects("inf"));
    EXPECT_TRUE(rejects("-1s"));
    EXPECT_TRUE(rejects("1m30"));  // a bare number only on its own
    EXPECT_TRUE(rejects("2 parsecs"));
    EXPECT_TRUE(rejects("1..2s"));
    EXPECT_TRUE(rejects("1e400s"));
    EXPECT_TRUE(rejects("99999999999h"));
}

}  // namespace
