#include "netfuzz/batch.hpp"

#include <fmt/format.h>
#include <poll.h>
#include <sys/socket.h>

#include <algorithm>
#include <cerrno>

#include "codec/exception_code.hpp"
#include "codec/limits.hpp"
#include "codec/mbap.hpp"
#include "net/clock.hpp"
#include "netfuzz/executor.hpp"
#include "netfuzz/rules.hpp"

namespace mbstorm::netfuzz {

namespace lim = codec::limits;

struct BatchRunner::Lane {
    struct Frame {
        std::size_t case_index;
        RequestInfo info;
        std::size_t end = 0;  // offset in `out` just past this frame
        bool answered = false;
        bool exception = false;  // answered with an exception
        bool fence = false;
        bool barrier = false;  // what follows is sent once this is answered
    };
    std::unique_ptr<Link> link;
    std::vector<std::uint8_t> out, in;
    std::size_t out_pos = 0, in_pos = 0;
    std::size_t send_limit = 0;    // bytes of `out` that may be sent now
    std::size_t next_barrier = 0;  // index of the frame the limit waits for
    std::vector<Frame> frames;
    std::vector<std::int32_t> by_tid = std::vector<std::int32_t>(65536, -1);
    std::vector<std::size_t> cases;  // case indexes on this lane, in order
    bool done = false, failed = false, closed = false, fence_answered = false;
    bool suspect_all = false;

    void reset_round() {
        for (const Frame& f : frames) by_tid[f.info.header.transaction_id] = -1;
        frames.clear();
        cases.clear();
        out.clear();
        in.clear();
        out_pos = in_pos = send_limit = next_barrier = 0;
        done = failed = closed = fence_answered = suspect_all = false;
    }

    // Moves the send limit past every barrier whose frame is answered (or owes nothing).
    void advance_limit() {
        while (next_barrier < frames.size()) {
            const Frame& f = frames[next_barrier];
            if (f.barrier && !f.answered && f.info.expect == Expect::Answer) {
                send_limit = f.end;
                return;
            }
            ++next_barrier;
        }
        send_limit = out.size();
    }

    // The first frame owed an answer that got none (frames.size() if there is none).
    std::size_t first_unanswered() const {
        for (std::size_t k = 0; k < frames.size(); ++k)
            if (!frames[k].answered && frames[k].info.expect == Expect::Answer) return k;
        return frames.size();
    }

    // The last answered request frame before `end` (frames.size() if there is none).
    std::size_t last_answered_before(std::size_t end) const {
        std::size_t found = frames.size();
        for (std::size_t k = 0; k < end && k < frames.size(); ++k)
            if (frames[k].answered && !frames[k].fence) found = k;
        return found;
    }
};

BatchRunner::BatchRunner(Connector& target, const TargetProfile& profile, BatchOptions options)
    : target_(target), profile_(profile), options_(options) {
    for (unsigned i = 0; i < std::max(1u, options_.lanes); ++i) lanes_.push_back(new Lane);
}

BatchRunner::~BatchRunner() {
    for (Lane* l : lanes_) delete l;
}

void BatchRunner::close_all() noexcept {
    for (Lane* l : lanes_) l->link.reset();
}

// What one call of run() shares between its steps.
struct BatchRunner::Round {
    const std::vector<Case>& cases;
    BatchResult result;
    std::vector<bool> suspect, judged, requeued;
    explicit Round(const std::vector<Case>& c)
        : cases(c), suspect(c.size(), false), judged(c.size(), false), requeued(c.size(), false) {}
};

BatchResult BatchRunner::run(const std::vector<Case>& cases) {
    Round round(cases);
    const std::size_t n_lanes = lanes_.size();
    for (Lane* l : lanes_) l->reset_round();
    // Build each lane's stream (stable from here on: RequestInfo views point into it).
    for (std::size_t i = 0; i < cases.size(); ++i) {
        Lane& l = *lanes_[i % n_lanes];
        l.cases.push_back(i);
        for (const Step& s : cases[i].steps)
            l.out.insert(l.out.end(), s.bytes.begin(), s.bytes.end());
    }
    for (Lane* l : lanes_) prepare(*l, round);
    exchange(round);
    if (round.result.cut_by_deadline) {
        round.result.suspects.clear();
        return std::move(round.result);
    }
    for (Lane* l : lanes_) conclude(*l, round);
    for (std::size_t i = 0; i < cases.size(); ++i)
        if (round.suspect[i]) round.result.suspects.push_back(i);
    return std::move(round.result);
}

// Frames the lane's cases (each well-framed by construction), appends the fence and connects.
void BatchRunner::prepare(Lane& l, Round& round) {
    if (l.cases.empty()) {
        l.done = true;
        return;
    }
    std::uint16_t fence_tid = 0xFE00;
    std::size_t off = 0;
    std::vector<std::size_t> sizes;
    for (std::size_t ci : l.cases) {
        std::size_t case_bytes = 0;
        for (const Step& s : round.cases[ci].steps) case_bytes += s.bytes.size();
        const std::size_t end = off + case_bytes;
        while (off + lim::kMbapHeader <= end) {
            const std::size_t size = codec::announced_adu_size(l.out.data() + off);
            Lane::Frame f{ci, {}, off + size};
            const std::uint16_t tid = codec::load_be16(l.out.data() + off);
            if (l.by_tid[tid] >= 0)
                round.suspect[ci] = true;  // cannot match: check it alone
            else
                l.by_tid[tid] = static_cast<std::int32_t>(l.frames.size());
            l.frames.push_back(f);
            sizes.push_back(size);
            off += size;
        }
        off = end;
    }
    while (l.by_tid[fence_tid] >= 0) ++fence_tid;
    const std::vector<std::uint8_t> fence = probe_frame(profile_, fence_tid);
    l.out.insert(l.out.end(), fence.begin(), fence.end());
    // Describe every frame against the final buffer.
    for (std::size_t k = 0, o = 0; k < l.frames.size(); ++k) {
        describe_request(codec::Bytes(l.out.data() + o, sizes[k]), profile_, l.frames[k].info);
        l.frames[k].barrier =
            options_.barrier_after_exception && owes_exception(l.frames[k].info, profile_);
        o += sizes[k];
    }
    Lane::Frame ff{static_cast<std::size_t>(-1), {}, l.out.size()};
    ff.fence = true;
    describe_request(codec::Bytes(l.out.data() + l.out.size() - fence.size(), fence.size()),
                     profile_, ff.info);
    l.by_tid[fence_tid] = static_cast<std::int32_t>(l.frames.size());
    l.frames.push_back(ff);
    l.advance_limit();
    if (l.link) return;
    int error = 0;
    l.link = target_.open(options_.timeout_ms, error);
    if (!l.link) {
        round.result.connect_failed = true;
        l.failed = true;
        l.done = true;
        l.suspect_all = true;
        return;
    }
}

void BatchRunner::fail(Lane& l, Round& round, bool closed) {
    l.failed = true;
    l.closed = closed;
    l.done = true;
    l.link.reset();
    round.result.lane_lost = true;
}

// Matches every complete answer received on the lane and judges it on the fly.
void BatchRunner::parse(Lane& l, Round& round) {
    BatchResult& result = round.result;
    while (l.in.size() - l.in_pos >= lim::kMbapHeader) {
        const std::uint8_t* p = l.in.data() + l.in_pos;
        const codec::MbapHeader h = codec::read_mbap_header(p);
        if (h.length < 2 || h.length > lim::kMaxMbapLength) {
            l.suspect_all = true;
            fail(l, round, false);
            return;
        }
        const std::size_t size = codec::adu_size(h);
        if (l.in.size() - l.in_pos < size) return;
        const std::int32_t k = l.by_tid[h.transaction_id];
        if (k >= 0 && l.frames[k].answered && !l.frames[k].fence) {
            round.suspect[l.frames[k].case_index] = true;  // answered twice: that one is odd
        } else if (k < 0 || l.frames[k].answered) {
            l.suspect_all = true;  // an answer nobody asked for: attribute in isolation
        } else {
            Lane::Frame& f = l.frames[k];
            f.answered = true;
            ++result.answers;
            f.exception =
                size > lim::kMbapHeader + 1 && (p[lim::kMbapHeader] & codec::kExceptionBit);
            if (f.exception &&
                p[lim::kMbapHeader + 1] ==
                    static_cast<std::uint8_t>(codec::ExceptionCode::ServerDeviceBusy))
                ++result.busy_answers;
            if (f.fence) {
                l.fence_answered = true;
            } else {
                Verdict v = judge_response(f.info, codec::Bytes(p, size), profile_);
                round.judged[f.case_index] = true;
                if (v) result.verdicts.emplace_back(f.case_index, std::move(v));
            }
        }
        l.in_pos += size;
    }
    l.advance_limit();
    if (l.fence_answered) l.done = true;
}

// Sends and receives on every lane until each is answered up to its fence, broke, went silent
// for the timeout or the deadline came.
void BatchRunner::exchange(Round& round) {
    // A lane that makes no progress for the timeout is given up (a barrier after an exception
    // may legitimately take a while: each answer restarts the clock).
    std::vector<std::int64_t> last_progress(lanes_.size(), net::now_ns());
    std::vector<pollfd> fds;
    std::vector<std::size_t> polled;
    for (;;) {
        fds.clear();
        polled.clear();
        bool buffered = false;
        const std::int64_t now = net::now_ns();
        std::int64_t wait_ns = options_.timeout_ms * net::kNsPerMs;
        if (cut_at_deadline(now, round)) return;
        if (options_.deadline_ns) wait_ns = std::min(wait_ns, options_.deadline_ns - now);
        for (std::size_t li = 0; li < lanes_.size(); ++li) {
            Lane& l = *lanes_[li];
            if (l.done) continue;
            const std::int64_t left = last_progress[li] + options_.timeout_ms * net::kNsPerMs - now;
            if (left <= 0) {
                fail(l, round, false);  // silence: the unanswered become suspects
                continue;
            }
            wait_ns = std::min(wait_ns, left);
            fds.push_back(
                pollfd{l.link->poll_fd(),
                       static_cast<short>(POLLIN | (l.out_pos < l.send_limit ? POLLOUT : 0)), 0});
            polled.push_back(li);
            buffered = buffered || l.link->has_buffered_input();
        }
        if (fds.empty()) return;
        const int rc = ::poll(
            fds.data(), fds.size(),
            buffered ? 0 : static_cast<int>(std::max<std::int64_t>(1, wait_ns / net::kNsPerMs)));
        if (rc < 0 || (rc == 0 && !buffered)) continue;
        for (std::size_t i = 0; i < fds.size(); ++i)
            transfer(*lanes_[polled[i]], round, fds[i].revents, last_progress[polled[i]]);
    }
}

bool BatchRunner::cut_at_deadline(std::int64_t now, Round& round) {
    if (!options_.deadline_ns || now < options_.deadline_ns) return false;
    // Out of time: what is unanswered now is neither a suspect nor a finding.
    for (Lane* l : lanes_)
        if (!l->done) {
            l->done = true;
            l->link.reset();
            round.result.cut_by_deadline = true;
        }
    return true;
}

// One lane's turn after poll(): sends what the limit allows, then reads and parses all there is.
void BatchRunner::transfer(Lane& l, Round& round, short revents, std::int64_t& last_progress) {
    if (revents & POLLOUT) {
        const ssize_t n = l.link->send(l.out.data() + l.out_pos, l.send_limit - l.out_pos);
        if (n > 0) {
            l.out_pos += static_cast<std::size_t>(n);
        } else if (n < 0 && n != -EAGAIN) {
            fail(l, round, true);
            return;
        }
    }
    if (!(revents & (POLLIN | POLLHUP | POLLERR)) && !l.link->has_buffered_input()) return;
    std::uint8_t buf[65536];
    for (;;) {
        const ssize_t n = l.link->recv(buf, sizeof buf);
        if (n > 0) {
            last_progress = net::now_ns();
            if (l.in_pos == l.in.size()) {
                l.in.clear();
                l.in_pos = 0;
            }
            l.in.insert(l.in.end(), buf, buf + n);
            parse(l, round);
            if (l.done) break;
            continue;
        }
        if (n != -EAGAIN) fail(l, round, true);
        break;
    }
}

// What a finished lane says: requests it went past unanswered are their own fault; a lane that
// broke blames the first request left unanswered or the one answered just before it, and what
// came after is run again in a later round.
void BatchRunner::conclude(Lane& l, Round& round) {
    if (l.cases.empty()) return;
    if (l.suspect_all) {
        for (std::size_t ci : l.cases) round.suspect[ci] = true;
        return;
    }
    if (!l.failed) {
        judge_passed_over(l, round);
        return;
    }
    round.result.breaks.push_back(describe_break(l, round));
}

// An intact lane answered what came after these requests: their silence is a hang of theirs.
void BatchRunner::judge_passed_over(Lane& l, Round& round) {
    for (const Lane::Frame& f : l.frames) {
        if (f.fence || f.answered || f.info.expect != Expect::Answer) continue;
        if (round.judged[f.case_index]) continue;
        round.judged[f.case_index] = true;
        round.result.verdicts.emplace_back(
            f.case_index,
            Verdict{Oracle::Hang,
                    unanswered_rule(false, culprit_text(round.cases[f.case_index].cls, &f.info)),
                    f.info.pdu.empty() ? -1 : f.info.pdu[0],
                    fmt::format("no answer to request {} (later requests were answered)",
                                hex(f.info.pdu, 16)),
                    "an answer", "silence"});
    }
}

LaneBreak BatchRunner::describe_break(Lane& l, Round& round) {
    const std::vector<Case>& cases = round.cases;
    const std::size_t first = l.first_unanswered();
    LaneBreak br;
    br.closed = l.closed;
    for (const Lane::Frame& f : l.frames) {
        if (f.fence || f.answered || f.info.expect != Expect::Answer) continue;
        if (br.unanswered.empty() || br.unanswered.back() != f.case_index)
            br.unanswered.push_back(f.case_index);
    }
    const std::size_t prev = l.last_answered_before(first);
    if (prev < l.frames.size()) {
        const Lane::Frame& f = l.frames[prev];
        br.has_previous = true;
        br.previous_case = f.case_index;
        br.previous_culprit = culprit_text(cases[f.case_index].cls, &f.info);
        br.previous_exception = f.exception;
        br.length_mismatch = pdu_length_mismatch(f.info);
        round.suspect[f.case_index] = true;
    }
    if (first < l.frames.size() && !l.frames[first].fence) {
        const Lane::Frame& f = l.frames[first];
        br.unanswered_case = f.case_index;
        br.unanswered_culprit = culprit_text(cases[f.case_index].cls, &f.info);
        br.unanswered_invalid = request_kind(f.info) != "valid";
        br.length_mismatch = br.length_mismatch || (br.closed && pdu_length_mismatch(f.info));
        round.suspect[f.case_index] = true;
        requeue_after(l, first, round);
    } else {
        br.unanswered_case = static_cast<std::size_t>(-1);  // only the fence went unanswered
        br.unanswered_culprit = "fence";
    }
    return br;
}

// The cases after the break's culprit never had a fair hearing: run them again (once) unless
// they are suspects or were judged already.
void BatchRunner::requeue_after(Lane& l, std::size_t culprit_frame, Round& round) {
    const std::size_t culprit = l.frames[culprit_frame].case_index;
    for (std::size_t k = culprit_frame + 1; k < l.frames.size(); ++k) {
        const std::size_t ci = l.frames[k].case_index;
        if (l.frames[k].fence || ci == culprit || round.suspect[ci] || round.requeued[ci] ||
            round.judged[ci])
            continue;
        round.requeued[ci] = true;
        round.result.requeue.push_back(ci);
    }
}

}  // namespace mbstorm::netfuzz
