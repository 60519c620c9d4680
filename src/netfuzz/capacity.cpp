#include "netfuzz/capacity.hpp"

#include <fmt/format.h>
#include <poll.h>
#include <sys/resource.h>
#include <sys/socket.h>

#include <algorithm>
#include <cerrno>
#include <vector>

#include "codec/limits.hpp"
#include "codec/mbap.hpp"
#include "net/clock.hpp"
#include "netfuzz/death_watch.hpp"
#include "netfuzz/executor.hpp"
#include "netfuzz/rules.hpp"
#include "netfuzz/wire.hpp"

namespace mbstorm::netfuzz {
namespace {

namespace lim = codec::limits;

// Connected: the probe is still to be sent.
enum class ConnState : std::uint8_t { Connected, Waiting, Answered, Refused };

struct Held {
    std::unique_ptr<Link> link;
    ConnState state = ConnState::Refused;
    std::vector<std::uint8_t> in;
};

// Sends the probe on every connection of `conns[from..]` and waits until each
// is answered or refused, or the time is up. Returns the number left unanswered (silent).
std::size_t probe_all(std::vector<Held>& conns, std::size_t from, const TargetProfile& profile,
                      int timeout_ms, std::int64_t deadline_ns) {
    const auto frame = probe_frame(profile, 0x0CA9);
    std::int64_t until = net::now_ns() + std::int64_t{timeout_ms} * net::kNsPerMs;
    if (deadline_ns) until = std::min(until, deadline_ns);
    std::vector<pollfd> ps;
    std::vector<std::size_t> idx;
    std::uint8_t buf[512];
    for (;;) {
        ps.clear();
        idx.clear();
        for (std::size_t i = from; i < conns.size(); ++i) {
            Held& h = conns[i];
            if (h.state == ConnState::Connected)
                ps.push_back(pollfd{h.link->poll_fd(), POLLOUT, 0});
            else if (h.state == ConnState::Waiting)
                ps.push_back(pollfd{h.link->poll_fd(), POLLIN, 0});
            else
                continue;
            idx.push_back(i);
        }
        if (ps.empty()) return 0;
        const std::int64_t left = until - net::now_ns();
        if (left <= 0) return ps.size();
        ::poll(ps.data(), ps.size(), static_cast<int>(std::max<std::int64_t>(1, left / 1000000)));
        for (std::size_t k = 0; k < ps.size(); ++k) {
            Held& h = conns[idx[k]];
            if (!ps[k].revents && !h.link->has_buffered_input()) continue;
            if (h.state == ConnState::Connected) {
                if (h.link->send(frame.data(), frame.size()) !=
                    static_cast<ssize_t>(frame.size())) {
                    h.state = ConnState::Refused;
                    h.link.reset();
                } else {
                    h.state = ConnState::Waiting;
                }
                continue;
            }
            const ssize_t n = h.link->recv(buf, sizeof buf);
            if (n > 0) {
                h.in.insert(h.in.end(), buf, buf + n);
                WireFrame answer;
                if (profile.framing != codec::Framing::Mbap
                        ? cut_frame(h.in, profile.framing, false, 0, answer) == WireCut::Frame
                        : h.in.size() >= lim::kMbapHeader &&
                              h.in.size() >= codec::announced_adu_size(h.in.data())) {
                    h.state = ConnState::Answered;
                    h.in.clear();
                }
            } else if (n != -EAGAIN) {
                h.state = ConnState::Refused;  // closed: a limit, which is allowed
                h.link.reset();
            }
        }
    }
}

// A lossy target drops a probe now and then as it drops any request, so the connections left
// silent are asked again: a connection the target does not serve stays silent however often it
// is asked. At most this many rounds, ended early by two in a row that answer none.
constexpr unsigned kMaxAskAgain = 4;

// Asks the connections of `conns[from..]` still waiting for an answer again; the number left
// silent.
std::size_t ask_silent_again(std::vector<Held>& conns, std::size_t from,
                             const TargetProfile& profile, std::size_t silent, int timeout_ms,
                             std::int64_t deadline_ns) {
    unsigned fruitless = 0;
    for (unsigned round = 0; silent > 0 && round < kMaxAskAgain && fruitless < 2; ++round) {
        for (std::size_t i = from; i < conns.size(); ++i)
            if (conns[i].state == ConnState::Waiting) conns[i].state = ConnState::Connected;
        const std::size_t still = probe_all(conns, from, profile, timeout_ms, deadline_ns);
        fruitless = still < silent ? 0 : fruitless + 1;
        silent = still;
        if (deadline_ns && net::now_ns() >= deadline_ns) break;
    }
    return silent;
}

}  // namespace

std::uint32_t connection_budget() {
    rlimit rl{};
    if (::getrlimit(RLIMIT_NOFILE, &rl) != 0) return 256;
    if (rl.rlim_cur < rl.rlim_max) {
        rlimit raised = rl;
        raised.rlim_cur = rl.rlim_max;
        if (::setrlimit(RLIMIT_NOFILE, &raised) == 0) rl = raised;
    }
    const rlim_t margin = 64;
    return rl.rlim_cur > margin
               ? static_cast<std::uint32_t>(std::min<rlim_t>(rl.rlim_cur - margin, 1u << 20))
               : 0;
}

CapacityResult check_capacity(Connector& target, const TargetProfile& profile,
                              std::uint32_t max_connections, int timeout_ms,
                              std::int64_t deadline_ns, DeathWatch* watch) {
    CapacityResult out;
    max_connections = std::min({max_connections, connection_budget(), target.max_links()});
    std::vector<Held> conns;
    conns.reserve(max_connections);
    auto out_of_time = [&] { return deadline_ns && net::now_ns() >= deadline_ns; };
    for (std::uint32_t step = 16; !out_of_time();) {
        const std::uint32_t goal = std::min(step, max_connections);
        const std::size_t from = conns.size();
        // A target at its limit may leave connects pending: once one times out, the rest of
        // the step counts as refused without waiting for each.
        bool timed_out = false;
        while (conns.size() < goal) {
            Held h;
            int error = 0;
            if (!timed_out) h.link = target.open(timeout_ms, error);
            timed_out = timed_out || error == ETIMEDOUT;
            h.state = h.link ? ConnState::Connected : ConnState::Refused;
            conns.push_back(std::move(h));
        }
        // A slow target gets three timeouts, and 2 ms more per new connection, to answer a
        // whole step: slow is not unserved.
        const int wait_ms = 3 * timeout_ms + 2 * static_cast<int>(conns.size() - from);
        const std::size_t silent = ask_silent_again(
            conns, from, profile, probe_all(conns, from, profile, wait_ms, deadline_ns), timeout_ms,
            deadline_ns);
        out.opened = static_cast<std::uint32_t>(conns.size());
        if (watch && watch->died(50)) {
            out.target_down = true;
            out.verdict = Verdict{
                Oracle::Crash,
                target_down_rule(kCapacityCulprit),
                -1,
                fmt::format("the target's process died with {} connections opened (every idle "
                            "connection it held was closed at once)",
                            conns.size()),
                "the target refuses or closes connections beyond its limit and keeps running",
                fmt::format("all connections dropped at {} open", conns.size())};
            return out;
        }
        if (out_of_time()) break;
        std::uint32_t refused = 0;
        for (const Held& h : conns) refused += h.state == ConnState::Refused;
        out.refused = refused;
        if (silent > 0) {
            out.verdict = Verdict{
                Oracle::Hang,
                kCapacityUnservedRule,
                -1,
                fmt::format("with {} connections open, {} newly accepted connection(s) got no "
                            "answer within {} ms",
                            conns.size(), silent, wait_ms),
                "every accepted connection is served (or refused, or closed, at a limit)",
                fmt::format("{} of {} new connections silent", silent, conns.size() - from)};
            break;
        }
        // The oldest connection that is still open must still answer.
        std::size_t oldest = conns.size();
        for (std::size_t i = 0; i < from; ++i)
            if (conns[i].state == ConnState::Answered) {
                oldest = i;
                break;
            }
        if (oldest < conns.size()) {
            conns[oldest].state = ConnState::Connected;  // sends the probe again
            const std::size_t silent_from_oldest =
                probe_all(conns, oldest, profile, timeout_ms, deadline_ns);
            if (conns[oldest].state == ConnState::Waiting)
                ask_silent_again(conns, oldest, profile, silent_from_oldest, timeout_ms,
                                 deadline_ns);
            if (conns[oldest].state == ConnState::Waiting && !out_of_time()) {
                out.verdict = Verdict{
                    Oracle::Hang,
                    kCapacityExistingUnservedRule,
                    -1,
                    fmt::format("with {} connections open, the oldest one stopped answering",
                                conns.size()),
                    "existing connections keep being served",
                    fmt::format("no answer within {} ms", timeout_ms)};
                break;
            }
        }
        out.held = static_cast<std::uint32_t>(conns.size() - refused);
        if (goal >= max_connections) break;
        step *= 4;
    }
    conns.clear();
    if (probe_target(target, profile, timeout_ms) == ProbeResult::ConnectFailed) {
        out.target_down = true;
        if (!out.verdict)
            out.verdict = Verdict{Oracle::Crash,
                                  target_down_rule(kCapacityCulprit),
                                  -1,
                                  fmt::format("target stopped accepting connections after "
                                              "holding {} connections",
                                              out.held),
                                  "the target accepts and serves a fresh connection",
                                  "connect failed"};
    }
    return out;
}

}  // namespace mbstorm::netfuzz
