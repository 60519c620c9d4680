// A frame in pieces reaches the target as separate reads however slow the target is: the
// executor sends the next piece only once the target's program has read the one before (its
// socket's receive queue, from the kernel's socket diagnostics). Against a server that reads
// 5 ms after each wakeup, a fixed 50 µs gap alone would hand it both pieces in one read.
#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <vector>

#include "fuzz_test_support.hpp"
#include "netfuzz/campaign.hpp"
#include "netfuzz/executor.hpp"
#include "netfuzz/finding.hpp"
#include "netfuzz/oracle.hpp"

using namespace mbstorm;
using namespace mbstorm::netfuzz;

namespace {

// Read holding registers 0x0010, quantity 2 (any valid request will do).
const std::vector<std::uint8_t> kRead = {0x03, 0x00, 0x10, 0x00, 0x02};

struct SlowSplitServer {
    std::unique_ptr<mbstorm::test::Target> process;
    std::unique_ptr<TcpConnector> connector;
    TargetProfile profile;

    bool start() {
        process = std::make_unique<mbstorm::test::Target>(
            std::vector<std::string>{mbstorm::test::tool_path("broken_server_split_close"),
                                     "--port", "0", "--exit-after-s", "60"});
        const std::string line = process->wait_for_line("PORT ");
        if (line.empty()) return false;
        const Result<net::Endpoint> ep = net::parse_endpoint("127.0.0.1:" + line.substr(5));
        if (!ep.ok()) return false;
        connector = std::make_unique<TcpConnector>(*ep);
        return discover_target(*connector, 1, 1000, profile).ok();
    }

    Execution run(std::uint32_t cut, std::uint32_t gap_us, int settle_ms = 0) {
        const auto f = frame_pdu(kRead, 0x0101, 1);
        Case c;
        c.cls = MutationClass::Split;
        c.function = kRead[0];
        c.steps.push_back(Step{Op::Send, 0, 0, 0, {f.begin(), f.begin() + cut}});
        if (cut < f.size())
            c.steps.push_back(Step{Op::Send, 0, gap_us, 0, {f.begin() + cut, f.end()}});
        ExecOptions o;
        o.timeout_ms = 500;
        o.piece_settle_ms = settle_ms;
        return execute_case(c, *connector, profile, o);
    }
};

}  // namespace

TEST(SplitDelivery, EachPieceIsAReadOfItsOwnOnASlowServer) {
    SlowSplitServer s;
    ASSERT_TRUE(s.start());
    for (int run = 0; run < 5; ++run) {
        const Execution ex = s.run(3, 50);
        // The close comes once the server has acted on the piece: before the rest went out
        // (closes-on-partial-frame) or, on a loaded machine, just after it
        // (close-with-request-pending/partial-frame). One root cause either way; without the
        // wait the pieces meet in one read and there is no finding at all.
        EXPECT_EQ(ex.verdict.oracle, Oracle::UnexpectedClose) << ex.verdict.summary;
        EXPECT_EQ(root_cause_key(ex.verdict), std::string("stream:") + kPartialFrameFamily)
            << ex.verdict.summary;
    }
}

TEST(SplitDelivery, AWholeFrameAndALongPieceAreAnswered) {
    SlowSplitServer s;
    ASSERT_TRUE(s.start());
    // The same server answers a frame sent at once, and one whose first piece holds a whole
    // header: the verdict above is about the piece, not the request.
    EXPECT_FALSE(s.run(12, 0).verdict) << s.run(12, 0).verdict.summary;
    const Execution long_piece = s.run(8, 50, 5);
    EXPECT_FALSE(long_piece.verdict) << long_piece.verdict.summary;
}
