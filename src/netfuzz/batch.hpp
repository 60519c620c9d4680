// The fast path: pipelinable cases spread over a few long-lived connections ("lanes"), many
// frames per send, each lane closed by an in-stream probe (the fence). Answers are matched by
// transaction id and judged on the fly; anything odd (a verdict, a close, a timeout, an answer
// nobody asked for) makes the affected cases suspects, which the campaign re-runs one by one
// on fresh connections (executor) to attribute and confirm the finding.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "net/socket.hpp"
#include "netfuzz/case.hpp"
#include "netfuzz/link.hpp"
#include "netfuzz/oracle.hpp"

namespace mbstorm::netfuzz {

struct BatchOptions {
    unsigned lanes = 4;
    int timeout_ms = 1000;  // silence for this long on a lane ends it
    // A request owed an exception ends a send: what follows waits for its answer (for targets
    // that drop what is pipelined behind an exception).
    bool barrier_after_exception = false;
    std::int64_t deadline_ns = 0;  // the campaign's deadline (0: none): lanes stop there
};

// Where a lane broke (closed, reset or went silent): the first request owed an answer that got
// none, and the request answered just before it. One of the two is at fault.
struct LaneBreak {
    std::size_t unanswered_case = 0;
    std::string unanswered_culprit;   // culprit_text of that request
    bool unanswered_invalid = false;  // the codec owes that request an exception
    bool has_previous = false;
    std::size_t previous_case = 0;
    std::string previous_culprit;
    bool previous_exception = false;  // the request before drew an exception
    bool closed = false;              // the lane was closed or reset, not silent
    // The request before or at the break has a PDU of the wrong length for its function code.
    bool length_mismatch = false;
    // Every case with a frame left unanswered, in the lane's order: where a target that died
    // or hung as a whole must be looked for (it may not answer what came before the culprit
    // either).
    std::vector<std::size_t> unanswered;
};

struct BatchResult {
    std::vector<std::size_t> suspects;  // case indexes to re-run in isolation, ascending
    // Verdicts seen on the fly, one per case at most (the case index with it).
    std::vector<std::pair<std::size_t, Verdict>> verdicts;
    std::vector<LaneBreak> breaks;
    // Cases whose frames came after a lane broke: never judged, to be run again.
    std::vector<std::size_t> requeue;
    std::uint64_t answers = 0, busy_answers = 0;  // busy: exception 06
    bool cut_by_deadline = false;  // stopped at the deadline: unanswered frames not judged
    bool lane_lost = false;        // a lane was closed, reset or timed out
    bool connect_failed = false;   // a lane could not (re)connect
};

class BatchRunner {
  public:
    BatchRunner(Connector& target, const TargetProfile& profile, BatchOptions options);
    ~BatchRunner();
    BatchRunner(const BatchRunner&) = delete;
    BatchRunner& operator=(const BatchRunner&) = delete;

    // Every case must be pipelinable. Case i goes to lane i % lanes.
    BatchResult run(const std::vector<Case>& cases);
    void close_all() noexcept;

  private:
    struct Lane;
    struct Round;
    void prepare(Lane& lane, Round& round);
    void exchange(Round& round);
    bool cut_at_deadline(std::int64_t now, Round& round);  // true: the deadline has come
    void transfer(Lane& lane, Round& round, short revents, std::int64_t& last_progress);
    void parse(Lane& lane, Round& round);
    void fail(Lane& lane, Round& round, bool closed);
    void conclude(Lane& lane, Round& round);
    void judge_passed_over(Lane& lane, Round& round);
    LaneBreak describe_break(Lane& lane, Round& round);
    void requeue_after(Lane& lane, std::size_t culprit_frame, Round& round);
    Connector& target_;
    const TargetProfile& profile_;
    BatchOptions options_;
    std::vector<Lane*> lanes_;
};

}  // namespace mbstorm::netfuzz
