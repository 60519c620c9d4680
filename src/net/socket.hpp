// Socket helpers: endpoints ("host:port", "[::1]:5020"), listeners, non-blocking connects,
// socket options and the open-files limit. Endpoints and listeners fail with an Error; the
// per-connection calls (connects, options) return -errno, the datum their callers count and
// classify failures by.
#pragma once

#include <netinet/in.h>
#include <sys/socket.h>

#include <cstdint>
#include <string>
#include <string_view>

#include "util/error.hpp"

namespace mbstorm::net {

struct Endpoint {
    sockaddr_storage addr{};
    socklen_t len = 0;

    int family() const noexcept { return addr.ss_family; }
    std::uint16_t port() const noexcept;
    void set_port(std::uint16_t port) noexcept;
    const sockaddr* sa() const noexcept { return reinterpret_cast<const sockaddr*>(&addr); }
    std::string to_string() const;  // "127.0.0.1:5020" or "[::1]:5020"
};

// The one target syntax of every subcommand: "host", "host:port", "[v6addr]", "[v6addr]:port"
// or a bare IPv6 literal ("::1", "fe80::1"; no port then). Splits without resolving; `port` is
// left as given (the caller's default) when the text has none. Port 0 is accepted here (a
// listener's "any port"); callers that connect refuse it. InvalidInput on bad text.
Error split_host_port(std::string_view text, std::string& host, std::uint16_t& port);

// split_host_port, then the host resolved (a name with getaddrinfo, first result; an empty
// host or "*" is every address). When the text has no port, `default_port` is used. A name
// that does not resolve is a Network error ("cannot resolve host 'x': ...").
Result<Endpoint> parse_endpoint(std::string_view text, std::uint16_t default_port = 502);

// RAII file descriptor.
class UniqueFd {
  public:
    UniqueFd() = default;
    explicit UniqueFd(int fd) noexcept : fd_(fd) {}
    ~UniqueFd() { reset(); }
    UniqueFd(UniqueFd&& o) noexcept : fd_(o.release()) {}
    UniqueFd& operator=(UniqueFd&& o) noexcept {
        if (this != &o) reset(o.release());
        return *this;
    }
    UniqueFd(const UniqueFd&) = delete;
    UniqueFd& operator=(const UniqueFd&) = delete;

    int get() const noexcept { return fd_; }
    bool valid() const noexcept { return fd_ >= 0; }
    int release() noexcept {
        int f = fd_;
        fd_ = -1;
        return f;
    }
    void reset(int fd = -1) noexcept;

  private:
    int fd_ = -1;
};

struct ListenOptions {
    int backlog = 4096;
    bool reuse_port = true;  // SO_REUSEPORT: one listener per thread on the same port
    bool nonblocking = true;
};

// socket + SO_REUSEADDR (+SO_REUSEPORT) + bind + listen. The listener, or a Network error
// whose message is the system's reason alone ("Address already in use"): the caller says what
// it was listening for.
Result<UniqueFd> listen_socket(const Endpoint& ep, const ListenOptions& options = {});

// Non-blocking socket + connect; EINPROGRESS counts as success. fd or -errno.
int connect_nonblocking(const Endpoint& ep) noexcept;

// Blocking connect (tests, tools). fd or -errno.
int connect_blocking(const Endpoint& ep) noexcept;
// Whether a connect completes within `timeout_ms` (the socket is closed again): 0, or the
// positive errno (ETIMEDOUT when it did not complete in time).
int connect_within(const Endpoint& ep, int timeout_ms) noexcept;

int set_nodelay(int fd, bool on = true) noexcept;
int set_nonblocking(int fd, bool on = true) noexcept;
// Port a bound socket actually got (for port 0). 0 on error.
std::uint16_t local_port(int fd) noexcept;
// Pending connect result (SO_ERROR): 0 or the positive errno.
int socket_error(int fd) noexcept;

// Raises RLIMIT_NOFILE soft limit towards `wanted` (up to the hard limit). Returns the
// resulting soft limit. When it stays below `wanted`, `message` explains what to do
// (ulimit -n / limits.conf / CAP_SYS_RESOURCE).
std::uint64_t raise_nofile_limit(std::uint64_t wanted, std::string* message = nullptr) noexcept;
// The current soft RLIMIT_NOFILE (0 when unknown).
std::uint64_t nofile_limit() noexcept;
// Descriptors this process has open now (0 when /proc/self/fd cannot be read).
std::uint64_t open_descriptor_count() noexcept;

}  // namespace mbstorm::net
