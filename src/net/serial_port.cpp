#include "net/serial_port.hpp"

#include <fcntl.h>
#include <poll.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

#include <fmt/format.h>

#include <cerrno>
#include <climits>
#include <cstdlib>
#include <cstring>
#include <string_view>

#include "net/clock.hpp"

namespace mbstorm::net {
namespace {

// The speeds termios names; others would need the non-portable BOTHER interface.
bool speed_constant(std::uint32_t baud, speed_t& out) noexcept {
    struct Entry {
        std::uint32_t baud;
        speed_t speed;
    };
    static constexpr Entry kSpeeds[] = {
        {50, B50},           {75, B75},           {110, B110},         {134, B134},
        {150, B150},         {200, B200},         {300, B300},         {600, B600},
        {1200, B1200},       {1800, B1800},       {2400, B2400},       {4800, B4800},
        {9600, B9600},       {19200, B19200},     {38400, B38400},     {57600, B57600},
        {115200, B115200},   {230400, B230400},   {460800, B460800},   {500000, B500000},
        {576000, B576000},   {921600, B921600},   {1000000, B1000000}, {1152000, B1152000},
        {1500000, B1500000}, {2000000, B2000000}, {2500000, B2500000}, {3000000, B3000000},
        {3500000, B3500000}, {4000000, B4000000},
    };
    for (const auto& e : kSpeeds) {
        if (e.baud == baud) {
            out = e.speed;
            return true;
        }
    }
    return false;
}

}  // namespace

unsigned bits_per_character(const SerialSettings& s) noexcept {
    return 1 + s.data_bits + (s.parity == Parity::None ? 0 : 1) + s.stop_bits;
}

std::int64_t character_time_ns(const SerialSettings& s) noexcept {
    const std::uint32_t baud = s.baud ? s.baud : 1;
    return static_cast<std::int64_t>(bits_per_character(s)) * kNsPerSec / baud;
}

std::int64_t intercharacter_timeout_ns(const SerialSettings& s) noexcept {
    if (s.baud > 19200) return 750'000;
    return character_time_ns(s) * 3 / 2;
}

std::int64_t interframe_silence_ns(const SerialSettings& s) noexcept {
    if (s.baud > 19200) return 1'750'000;
    return character_time_ns(s) * 7 / 2;
}

bool is_pseudo_terminal(const std::string& device) {
    char resolved[PATH_MAX];
    if (::realpath(device.c_str(), resolved) == nullptr) return false;
    return std::string_view(resolved).starts_with("/dev/pts/");
}

std::string describe(const SerialSettings& s) {
    const char parity = s.parity == Parity::None ? 'N' : s.parity == Parity::Even ? 'E' : 'O';
    return fmt::format("{} {}{}{}", s.baud, s.data_bits, parity, s.stop_bits);
}

Error SerialPort::open(const std::string& device, const SerialSettings& settings) {
    speed_t speed{};
    if (!speed_constant(settings.baud, speed))
        return Error(ErrorCode::InvalidInput,
                     fmt::format("{} baud is not a speed the tty interface offers (e.g. 9600, "
                                 "19200, 38400, 57600, 115200)",
                                 settings.baud));
    int fd = ::open(device.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) return from_errno(ErrorCode::Io, errno, "cannot open " + device);
    UniqueFd owned(fd);
    termios t{};
    if (::tcgetattr(fd, &t) != 0)
        return from_errno(ErrorCode::InvalidInput, errno, device + " is not a terminal");
    ::cfmakeraw(&t);
    t.c_cflag &= ~static_cast<tcflag_t>(CSIZE | PARENB | PARODD | CSTOPB | CRTSCTS);
    t.c_cflag |= CLOCAL | CREAD | (settings.data_bits == 7 ? CS7 : CS8);
    if (settings.parity != Parity::None) t.c_cflag |= PARENB;
    if (settings.parity == Parity::Odd) t.c_cflag |= PARODD;
    if (settings.stop_bits == 2) t.c_cflag |= CSTOPB;
    t.c_iflag &= ~static_cast<tcflag_t>(IXON | IXOFF | IXANY);
    t.c_cc[VMIN] = 0;
    t.c_cc[VTIME] = 0;
    ::cfsetispeed(&t, speed);
    ::cfsetospeed(&t, speed);
    // A pseudo-terminal keeps no parity bit, and glibc's tcsetattr then reports EINVAL after
    // the settings were applied: a pty's raw mode is all a test line needs.
    if (::tcsetattr(fd, TCSANOW, &t) != 0 && !(errno == EINVAL && is_pseudo_terminal(device)))
        return from_errno(ErrorCode::Io, errno,
                          fmt::format("cannot set {} to {}", device, describe(settings)));
    ::tcflush(fd, TCIOFLUSH);
    fd_ = std::move(owned);
    settings_ = settings;
    device_ = device;
    busy_until_ns_ = 0;
    last_rx_ns_ = 0;
    return Error::none();
}

ssize_t SerialPort::read_some(std::uint8_t* data, std::size_t size) noexcept {
    for (;;) {
        ssize_t n = ::read(fd_.get(), data, size);
        if (n > 0) {
            last_rx_ns_ = now_ns();
            return n;
        }
        if (n == 0) return 0;
        if (errno == EINTR) continue;
        if (errno == EAGAIN) return 0;
        return -errno;
    }
}

bool SerialPort::wait_readable(std::int64_t timeout_ns) const noexcept {
    const std::int64_t deadline = now_ns() + (timeout_ns > 0 ? timeout_ns : 0);
    for (;;) {
        const std::int64_t left = deadline - now_ns();
        timespec ts{static_cast<time_t>(left > 0 ? left / kNsPerSec : 0),
                    static_cast<long>(left > 0 ? left % kNsPerSec : 0)};
        pollfd p{fd_.get(), POLLIN, 0};
        int rc = ::ppoll(&p, 1, &ts, nullptr);
        if (rc > 0) return (p.revents & POLLIN) != 0 || (p.revents & (POLLERR | POLLHUP)) != 0;
        if (rc == 0) return false;
        if (errno != EINTR) return false;
    }
}

int SerialPort::send_frame(const std::uint8_t* data, std::size_t size,
                           std::int64_t silence_ns) noexcept {
    std::int64_t start = busy_until_ns_ + silence_ns;
    if (last_rx_ns_ + silence_ns > start) start = last_rx_ns_ + silence_ns;
    sleep_until_ns(start);
    return send_now(data, size);
}

int SerialPort::send_now(const std::uint8_t* data, std::size_t size) noexcept {
    last_send_start_ns_ = now_ns();
    for (std::size_t sent = 0; sent < size;) {
        ssize_t n = ::write(fd_.get(), data + sent, size - sent);
        if (n > 0) {
            sent += static_cast<std::size_t>(n);
            continue;
        }
        if (n < 0 && errno == EINTR) continue;
        if (n < 0 && errno != EAGAIN) return -errno;
        pollfd p{fd_.get(), POLLOUT, 0};
        if (::poll(&p, 1, 1000) == 0) return -ETIMEDOUT;
    }
    // The frame occupies the wire for its characters' time from now.
    busy_until_ns_ = now_ns() + static_cast<std::int64_t>(size) * character_time_ns(settings_);
    return 0;
}

void SerialPort::discard_input() noexcept {
    ::tcflush(fd_.get(), TCIFLUSH);
}

void sleep_until_ns(std::int64_t deadline_ns) noexcept {
    constexpr std::int64_t kSpin = 200'000;  // the scheduler's wake-up slack
    const std::int64_t coarse = deadline_ns - kSpin;
    if (coarse > now_ns()) {
        timespec ts{static_cast<time_t>(coarse / kNsPerSec), static_cast<long>(coarse % kNsPerSec)};
        while (::clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
        }
    }
    while (now_ns() < deadline_ns) {
    }
}

}  // namespace mbstorm::net
