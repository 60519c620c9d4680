// The one "did you mean" rule under subcommands, flags and YAML keys.
#include "util/closest_name.hpp"

#include <gtest/gtest.h>

#include <array>
#include <string_view>

namespace mbstorm::util {
namespace {

constexpr std::array<std::string_view, 5> kCommands{"run", "serve", "read", "write", "fuzz"};

TEST(EditDistance, CountsInsertionsDeletionsSubstitutionsAndSwaps) {
    EXPECT_EQ(edit_distance("", ""), 0u);
    EXPECT_EQ(edit_distance("", "abc"), 3u);
    EXPECT_EQ(edit_distance("abc", ""), 3u);
    EXPECT_EQ(edit_distance("conections", "connections"), 1u);    // insertion
    EXPECT_EQ(edit_distance("connectionss", "connections"), 1u);  // deletion
    EXPECT_EQ(edit_distance("depht", "depth"), 1u);               // swap of neighbours
    EXPECT_EQ(edit_distance("rnu", "run"), 1u);
    EXPECT_EQ(edit_distance("kitten", "sitting"), 3u);
}

TEST(ClosestName, SuggestsTheNearestCandidate) {
    EXPECT_EQ(closest_name("rnu", kCommands), "run");
    EXPECT_EQ(closest_name("srve", kCommands), "serve");
    EXPECT_EQ(closest_name("raed", kCommands), "read");
    EXPECT_EQ(closest_name("fuz", kCommands), "fuzz");
}

TEST(ClosestName, SuggestsNothingForAFarOrAnExactName) {
    EXPECT_EQ(closest_name("xyz", kCommands), "");
    EXPECT_EQ(closest_name("deploy", kCommands), "");
    EXPECT_EQ(closest_name("run", kCommands), "");
    constexpr std::array<std::string_view, 2> letters{"a", "b"};
    EXPECT_EQ(closest_name("c", letters), "");  // one edit, but the whole word
    EXPECT_EQ(closest_name("anything", std::span<const std::string_view>{}), "");
}

TEST(ClosestName, AllowsMoreEditsInLongerWords) {
    constexpr std::array<std::string_view, 2> keys{"connect_timeout", "connections"};
    EXPECT_EQ(closest_name("conect_timout", keys), "connect_timeout");  // two edits in 13
    EXPECT_EQ(closest_name("rn", kCommands), "run");                    // one edit in 2
    EXPECT_EQ(closest_name("ru_n", kCommands), "run");
}

}  // namespace
}  // namespace mbstorm::util
