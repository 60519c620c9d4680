#include "netfuzz/death_watch.hpp"

#include <poll.h>

#include <cerrno>

#include "net/clock.hpp"
#include "netfuzz/executor.hpp"

namespace mbstorm::netfuzz {

bool DeathWatch::arm() {
    links_.clear();
    for (unsigned i = 0; i < count_; ++i) {
        int error = 0;
        std::unique_ptr<Link> link = target_.open(timeout_ms_, error);
        if (link) links_.push_back(std::move(link));
    }
    armed_at_ = net::now_ns();
    // Answered after them, so they were accepted (a loaded target may take a few tries).
    for (int i = 0; profile_ && !links_.empty() && i < 3; ++i)
        if (probe_target(target_, *profile_, timeout_ms_) == ProbeResult::Ok) break;
    return !links_.empty();
}

int DeathWatch::gone(Link& link) {
    pollfd p{link.poll_fd(), POLLIN, 0};
    if (::poll(&p, 1, 0) <= 0 || !(p.revents & (POLLIN | POLLHUP | POLLERR))) return 0;
    std::uint8_t buf[512];
    for (;;) {
        const ssize_t n = link.recv(buf, sizeof buf);
        if (n == -EAGAIN) return 0;
        if (n <= 0) return 1;
    }
}

bool DeathWatch::died(int wait_ms) {
    if (links_.empty()) return false;
    const std::int64_t until = net::now_ns() + std::int64_t{wait_ms} * net::kNsPerMs;
    for (;;) {
        std::size_t closed = 0;
        for (auto& link : links_) closed += gone(*link);
        if (closed == links_.size()) {
            ++deaths_;
            links_.clear();
            return true;
        }
        // None gone: alive. Some gone: a dying process may still be closing the others.
        if (closed == 0 || net::now_ns() >= until) return false;
        ::poll(nullptr, 0, 5);
    }
}

void DeathWatch::refresh(std::int64_t max_age_ms) {
    // Disarmed (the target could not be reached when last armed): try again.
    if (!links_.empty() && net::now_ns() - armed_at_ < max_age_ms * net::kNsPerMs) return;
    arm();
}

}  // namespace mbstorm::netfuzz
