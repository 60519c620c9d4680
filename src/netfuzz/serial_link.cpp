#include "netfuzz/serial_link.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cerrno>

#include "net/clock.hpp"

namespace mbstorm::netfuzz {
namespace {

// How long the line must stay silent before a new link is handed out.
constexpr std::int64_t kQuietLineMs = 5;

}  // namespace

ssize_t SerialLink::send(const std::uint8_t* data, std::size_t size) noexcept {
    const int rc = port_->send_frame(data, size, net::interframe_silence_ns(port_->settings()));
    return rc < 0 ? rc : static_cast<ssize_t>(size);
}

ssize_t SerialLink::recv(std::uint8_t* data, std::size_t size) noexcept {
    const ssize_t n = port_->read_some(data, size);
    if (n == 0) return -EAGAIN;  // a line never closes: nothing there yet
    return n;
}

std::unique_ptr<Link> SerialConnector::open(int timeout_ms, int& error) {
    error = 0;
    if (!port_) {
        auto port = std::make_shared<net::SerialPort>();
        if (!port->open(device_, settings_).ok()) {
            error = errno ? errno : ENODEV;
            return nullptr;
        }
        port_ = std::move(port);
    }
    // A fresh link starts on a quiet line: what is still arriving (a slow slave's late answer
    // to the last link's request) is read and dropped until the line is silent for a while.
    port_->discard_input();
    const std::int64_t quiet_ns = std::max<std::int64_t>(4 * net::interframe_silence_ns(settings_),
                                                         kQuietLineMs * net::kNsPerMs);
    const std::int64_t give_up = net::now_ns() + std::int64_t{timeout_ms} * net::kNsPerMs;
    while (port_->wait_readable(quiet_ns) && net::now_ns() < give_up) {
        std::uint8_t drop[256];
        if (port_->read_some(drop, sizeof drop) < 0) break;
    }
    return std::make_unique<SerialLink>(port_);
}

std::string SerialConnector::describe() const {
    return fmt::format("{} ({} {})", device_, net::describe(settings_),
                       codec::framing_name(framing_));
}

}  // namespace mbstorm::netfuzz
