// The pieces every worker loop shares: the wait-error filter and the dirty list.
#include <gtest/gtest.h>

#include <vector>

#include "net/completion_loop.hpp"

namespace mbstorm::net {
namespace {

TEST(CompletionLoop, OnlyRealWaitErrorsCountAsFailures) {
    EXPECT_FALSE(wait_failed(0));
    EXPECT_FALSE(wait_failed(3));
    EXPECT_FALSE(wait_failed(-ETIME));
    EXPECT_FALSE(wait_failed(-EINTR));
    EXPECT_FALSE(wait_failed(-EAGAIN));
    EXPECT_FALSE(wait_failed(-EBUSY));
    EXPECT_TRUE(wait_failed(-EBADF));
    EXPECT_TRUE(wait_failed(-EFAULT));
}

TEST(CompletionLoop, DirtyListListsEachConnectionOnceInMarkingOrder) {
    DirtyList list;
    list.reserve(4);
    bool f0 = false, f2 = false, f3 = false;
    list.mark(f2, 2);
    list.mark(f0, 0);
    list.mark(f2, 2);
    list.mark(f3, 3);
    list.mark(f0, 0);
    std::vector<std::uint32_t> seen;
    list.drain([&](std::uint32_t index) { seen.push_back(index); });
    EXPECT_EQ(seen, (std::vector<std::uint32_t>{2, 0, 3}));
    // Drained: empty until marked again, and a flag left set keeps its connection out.
    seen.clear();
    list.drain([&](std::uint32_t index) { seen.push_back(index); });
    EXPECT_TRUE(seen.empty());
    f0 = false;
    list.mark(f0, 0);
    list.mark(f2, 2);
    list.drain([&](std::uint32_t index) { seen.push_back(index); });
    EXPECT_EQ(seen, (std::vector<std::uint32_t>{0}));
}

}  // namespace
}  // namespace mbstorm::net
