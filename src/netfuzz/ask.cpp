#include "netfuzz/ask.hpp"

#include <poll.h>

#include <cerrno>
#include <memory>

#include "codec/limits.hpp"
#include "codec/mbap.hpp"
#include "net/clock.hpp"
#include "netfuzz/wire.hpp"

namespace mbstorm::netfuzz {
namespace {

namespace lim = codec::limits;
using Pdu = std::vector<std::uint8_t>;

// RTU and ASCII (no transaction ids): each frame in turn on one link, its answer awaited (or
// the timeout) before the next goes out. The answers' PDUs by frame.
std::vector<Pdu> one_by_one(Connector& target, const std::vector<Pdu>& frames, int timeout_ms,
                            bool& connected) {
    std::vector<Pdu> answers(frames.size());
    int error = 0;
    const std::unique_ptr<Link> link = target.open(timeout_ms, error);
    connected = link != nullptr;
    if (!link) return answers;
    for (std::size_t i = 0; i < frames.size(); ++i) {
        if (link->send(frames[i].data(), frames[i].size()) !=
            static_cast<ssize_t>(frames[i].size()))
            return answers;
        Pdu in;
        const std::int64_t deadline = net::now_ns() + timeout_ms * net::kNsPerMs;
        for (;;) {
            const std::int64_t left = (deadline - net::now_ns()) / net::kNsPerMs;
            if (left <= 0) break;
            if (!wait_readable(*link, static_cast<int>(left))) continue;
            std::uint8_t buf[1024];
            const ssize_t n = link->recv(buf, sizeof buf);
            if (n == -EAGAIN) continue;
            if (n <= 0) return answers;
            in.insert(in.end(), buf, buf + n);
            WireFrame f;
            const WireCut cut = cut_frame(in, target.framing(), false, 0, f);
            if (cut == WireCut::Lost) return answers;
            if (cut == WireCut::Frame) {
                if (f.discard.empty())
                    answers[i].assign(f.mbap.begin() + lim::kMbapHeader, f.mbap.end());
                break;
            }
        }
    }
    return answers;
}

}  // namespace

// Sends all frames at once on one connection and collects answers by transaction id until
// the last one is answered, the connection closes or the time is up.
std::vector<Pdu> ask_pipelined(Connector& target, const std::vector<Pdu>& frames, int timeout_ms,
                               bool& connected) {
    if (target.framing() != codec::Framing::Mbap)
        return one_by_one(target, frames, timeout_ms, connected);
    std::vector<Pdu> answers(frames.size());
    int error = 0;
    const std::unique_ptr<Link> link = target.open(timeout_ms, error);
    connected = link != nullptr;
    if (!link) return answers;
    Pdu out;
    for (const Pdu& f : frames) out.insert(out.end(), f.begin(), f.end());
    std::size_t sent = 0;
    Pdu in;
    std::size_t pos = 0;
    const std::int64_t deadline = net::now_ns() + timeout_ms * net::kNsPerMs;
    while (net::now_ns() < deadline && answers.back().empty()) {
        pollfd p{link->poll_fd(), static_cast<short>(POLLIN | (sent < out.size() ? POLLOUT : 0)),
                 0};
        const bool buffered = link->has_buffered_input();
        if (::poll(&p, 1, buffered ? 0 : 20) <= 0 && !buffered) continue;
        if (p.revents & POLLOUT) {
            const ssize_t n = link->send(out.data() + sent, out.size() - sent);
            if (n > 0) sent += static_cast<std::size_t>(n);
        }
        if ((p.revents & (POLLIN | POLLHUP | POLLERR)) || buffered) {
            std::uint8_t buf[8192];
            const ssize_t n = link->recv(buf, sizeof buf);
            if (n <= 0 && n != -EAGAIN) break;
            if (n > 0) in.insert(in.end(), buf, buf + n);
            while (in.size() - pos >= lim::kMbapHeader) {
                const auto h = codec::read_mbap_header(in.data() + pos);
                if (h.length < 2 || h.length > lim::kMaxMbapLength) return answers;
                if (in.size() - pos < codec::adu_size(h)) break;
                if (h.transaction_id < answers.size())
                    answers[h.transaction_id].assign(
                        in.begin() + static_cast<std::ptrdiff_t>(pos + 7),
                        in.begin() + static_cast<std::ptrdiff_t>(pos + codec::adu_size(h)));
                pos += codec::adu_size(h);
            }
        }
    }
    return answers;
}

}  // namespace mbstorm::netfuzz
