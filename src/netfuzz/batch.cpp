#include "netfuzz/batch.hpp"

#include <poll.h>
#include <sys/socket.h>

#include <algorithm>
#include <cerrno>

#include "codec/limits.hpp"
#include "net/clock.hpp"
#include "netfuzz/executor.hpp"

namespace mbstorm::netfuzz {

namespace lim = codec::limits;

struct BatchRunner::Lane {
    struct Frame {
        std::size_t case_index;
        RequestInfo info;
        bool answered = false;
        bool fence = false;
    };
    net::UniqueFd fd;
    std::vector<std::uint8_t> out, in;
    std::size_t out_pos = 0, in_pos = 0;
    std::vector<Frame> frames;
    std::vector<std::int32_t> by_tid = std::vector<std::int32_t>(65536, -1);
    std::vector<std::size_t> cases;  // case indexes on this lane, in order
    bool done = false, failed = false, fence_answered = false;
    bool suspect_all = false;

    void reset_round() {
        for (const Frame& f : frames) by_tid[f.info.header.transaction_id] = -1;
        frames.clear();
        cases.clear();
        out.clear();
        in.clear();
        out_pos = in_pos = 0;
        done = failed = fence_answered = suspect_all = false;
    }
};

BatchRunner::BatchRunner(const net::Endpoint& target, const TargetProfile& profile,
                         BatchOptions options)
    : target_(target), profile_(profile), options_(options) {
    for (unsigned i = 0; i < std::max(1u, options_.lanes); ++i) lanes_.push_back(new Lane);
}

BatchRunner::~BatchRunner() {
    for (Lane* l : lanes_) delete l;
}

void BatchRunner::close_all() noexcept {
    for (Lane* l : lanes_) l->fd.reset();
}

BatchResult BatchRunner::run(const std::vector<Case>& cases) {
    BatchResult result;
    std::vector<bool> suspect(cases.size(), false);
    const std::size_t n_lanes = lanes_.size();
    for (Lane* l : lanes_) l->reset_round();
    // Build each lane's stream (stable from here on: RequestInfo views point into it).
    for (std::size_t i = 0; i < cases.size(); ++i) {
        Lane& l = *lanes_[i % n_lanes];
        l.cases.push_back(i);
        for (const Step& s : cases[i].steps)
            l.out.insert(l.out.end(), s.bytes.begin(), s.bytes.end());
    }
    for (Lane* lp : lanes_) {
        Lane& l = *lp;
        if (l.cases.empty()) {
            l.done = true;
            continue;
        }
        std::uint16_t fence_tid = 0xFE00;
        std::vector<std::uint8_t> fence;
        // Frames: the lane's cases in order (each well-framed by construction).
        std::size_t off = 0;
        for (std::size_t ci : l.cases) {
            std::size_t case_bytes = 0;
            for (const Step& s : cases[ci].steps) case_bytes += s.bytes.size();
            const std::size_t end = off + case_bytes;
            while (off + lim::kMbapHeader <= end) {
                const std::size_t size = 6u + codec::load_be16(l.out.data() + off + 4);
                Lane::Frame f{ci, {}, false, false};
                describe_request(codec::Bytes(l.out.data() + off, size), profile_, f.info);
                const std::uint16_t tid = f.info.header.transaction_id;
                if (l.by_tid[tid] >= 0)
                    suspect[ci] = true;  // cannot match: check it alone
                else
                    l.by_tid[tid] = static_cast<std::int32_t>(l.frames.size());
                l.frames.push_back(f);
                off += size;
            }
            off = end;
        }
        while (l.by_tid[fence_tid] >= 0) ++fence_tid;
        fence = probe_frame(profile_, fence_tid);
        l.out.insert(l.out.end(), fence.begin(), fence.end());
        // The fence's own frame (describe after the insert: `out` may have moved).
        for (std::size_t k = 0, o = 0; k < l.frames.size(); ++k) {
            // Re-point every view at the final buffer.
            const std::size_t size = l.frames[k].info.pdu.size() + lim::kMbapHeader;
            describe_request(codec::Bytes(l.out.data() + o, size), profile_, l.frames[k].info);
            o += size;
        }
        Lane::Frame ff{static_cast<std::size_t>(-1), {}, false, true};
        describe_request(codec::Bytes(l.out.data() + l.out.size() - fence.size(), fence.size()),
                         profile_, ff.info);
        l.by_tid[fence_tid] = static_cast<std::int32_t>(l.frames.size());
        l.frames.push_back(ff);
        if (!l.fd.valid()) {
            const int fd = connect_with_timeout(target_, options_.timeout_ms);
            if (fd < 0) {
                result.connect_failed = true;
                l.failed = true;
                l.done = true;
                l.suspect_all = true;
                continue;
            }
            l.fd.reset(fd);
        }
    }

    auto fail_lane = [&](Lane& l) {
        l.failed = true;
        l.done = true;
        l.fd.reset();
        result.lane_lost = true;
    };
    auto parse = [&](Lane& l) {
        while (l.in.size() - l.in_pos >= lim::kMbapHeader) {
            const std::uint8_t* p = l.in.data() + l.in_pos;
            const codec::MbapHeader h = codec::read_mbap_header(p);
            if (h.length < 2 || h.length > lim::kMaxMbapLength) {
                l.suspect_all = true;
                fail_lane(l);
                return;
            }
            const std::size_t size = 6u + h.length;
            if (l.in.size() - l.in_pos < size) return;
            const std::int32_t k = l.by_tid[h.transaction_id];
            if (k < 0 || l.frames[k].answered) {
                l.suspect_all = true;  // an answer nobody asked for: attribute in isolation
            } else {
                Lane::Frame& f = l.frames[k];
                f.answered = true;
                if (f.fence) {
                    l.fence_answered = true;
                } else {
                    const Verdict v = judge_response(f.info, codec::Bytes(p, size), profile_);
                    if (v)
                        suspect[f.case_index] = true;
                    else if (f.info.status.ok() && !(p[7] & codec::kExceptionBit))
                        result.answered_valid.push_back(f.case_index);
                }
            }
            l.in_pos += size;
        }
        if (l.fence_answered) l.done = true;
    };

    const std::int64_t deadline = net::now_ns() + options_.timeout_ms * net::kNsPerMs;
    std::vector<pollfd> fds;
    std::vector<Lane*> polled;
    std::uint8_t buf[65536];
    for (;;) {
        fds.clear();
        polled.clear();
        for (Lane* l : lanes_) {
            if (l->done) continue;
            fds.push_back(
                pollfd{l->fd.get(),
                       static_cast<short>(POLLIN | (l->out_pos < l->out.size() ? POLLOUT : 0)), 0});
            polled.push_back(l);
        }
        if (fds.empty()) break;
        const std::int64_t left = deadline - net::now_ns();
        if (left <= 0) {
            for (Lane* l : polled) fail_lane(*l);  // timeout: the unanswered become suspects
            break;
        }
        const int rc = ::poll(fds.data(), fds.size(),
                              static_cast<int>(std::max<std::int64_t>(1, left / net::kNsPerMs)));
        if (rc <= 0) continue;
        for (std::size_t i = 0; i < fds.size(); ++i) {
            Lane& l = *polled[i];
            if (fds[i].revents & POLLOUT) {
                const ssize_t n = ::send(l.fd.get(), l.out.data() + l.out_pos,
                                         l.out.size() - l.out_pos, MSG_NOSIGNAL);
                if (n > 0)
                    l.out_pos += static_cast<std::size_t>(n);
                else if (n < 0 && errno != EAGAIN && errno != EINTR) {
                    fail_lane(l);
                    continue;
                }
            }
            if (fds[i].revents & (POLLIN | POLLHUP | POLLERR)) {
                for (;;) {
                    const ssize_t n = ::recv(l.fd.get(), buf, sizeof buf, 0);
                    if (n > 0) {
                        if (l.in_pos == l.in.size()) {
                            l.in.clear();
                            l.in_pos = 0;
                        }
                        l.in.insert(l.in.end(), buf, buf + n);
                        parse(l);
                        if (l.done) break;
                        continue;
                    }
                    if (n == 0 || (errno != EAGAIN && errno != EINTR)) fail_lane(l);
                    break;
                }
            }
        }
    }
    for (Lane* lp : lanes_) {
        Lane& l = *lp;
        if (l.cases.empty()) continue;
        if (l.suspect_all) {
            for (std::size_t ci : l.cases) suspect[ci] = true;
            continue;
        }
        // Unanswered frames that owed an answer (after the fence, or on a failed lane).
        for (const Lane::Frame& f : l.frames)
            if (!f.fence && !f.answered && f.info.expect == Expect::Answer)
                suspect[f.case_index] = true;
        if (l.failed) {
            // A crash or close may have been caused by an answered frame that the server
            // choked on afterwards: the last answered case is suspect too.
            for (const Lane::Frame& f : l.frames)
                if (!f.fence && !f.answered) suspect[f.case_index] = true;
            std::size_t last = l.cases.front();
            for (const Lane::Frame& f : l.frames)
                if (!f.fence && f.answered) last = f.case_index;
            suspect[last] = true;
        }
    }
    for (std::size_t i = 0; i < cases.size(); ++i)
        if (suspect[i]) result.suspects.push_back(i);
    return result;
}

}  // namespace mbstorm::netfuzz
