// Idle sentinel connections held open across cases, so that a crash is a crash however fast
// the target comes back. Under a supervisor (systemd Restart=always, a container runtime, a
// PLC watchdog) a crashed server listens again within milliseconds: a fresh probe finds it up,
// but every connection the dead process held was closed at the same moment. The sentinels are
// such connections, never sent anything (so no request of theirs can be at fault), replaced
// now and then so that a device's idle timeout is not taken for a death.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "netfuzz/link.hpp"
#include "netfuzz/oracle.hpp"

namespace mbstorm::netfuzz {

class DeathWatch {
  public:
    // With a `profile`, arm() waits for a fresh connection's probe to be answered, so that the
    // target has accepted the sentinels before it (a connection still in the listen backlog
    // outlives a crashed process and goes to its successor).
    explicit DeathWatch(Connector& target, unsigned sentinels = 3, int timeout_ms = 1000,
                        const TargetProfile* profile = nullptr)
        : target_(target), count_(sentinels), timeout_ms_(timeout_ms), profile_(profile) {}

    // Opens the sentinels (closing any left). False when none could be opened.
    bool arm();
    void disarm() { links_.clear(); }
    bool armed() const noexcept { return !links_.empty(); }
    // True when every sentinel was closed or reset by the target, waiting up to `wait_ms` for
    // the last of them once one has gone (a dying process closes them one after another). The
    // sentinels are disarmed then: arm() again once the target is back.
    bool died(int wait_ms = 100);
    // Replaces sentinels older than `max_age_ms` (a device may close idle connections). Call
    // it only right after died() said no.
    void refresh(std::int64_t max_age_ms = 2000);
    std::uint64_t deaths_seen() const noexcept { return deaths_; }

  private:
    // 1: closed or reset; 0: open and quiet; data is read and dropped.
    int gone(Link& link);

    Connector& target_;
    unsigned count_;
    int timeout_ms_;
    const TargetProfile* profile_;
    std::vector<std::unique_ptr<Link>> links_;
    std::int64_t armed_at_ = 0;
    std::uint64_t deaths_ = 0;
};

}  // namespace mbstorm::netfuzz
