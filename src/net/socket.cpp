#include "net/socket.hpp"

#include <arpa/inet.h>
#include <dirent.h>
#include <fcntl.h>
#include <netdb.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cstring>

namespace mbstorm::net {

void UniqueFd::reset(int fd) noexcept {
    if (fd_ >= 0) ::close(fd_);
    fd_ = fd;
}

std::uint16_t Endpoint::port() const noexcept {
    if (addr.ss_family == AF_INET)
        return ntohs(reinterpret_cast<const sockaddr_in*>(&addr)->sin_port);
    if (addr.ss_family == AF_INET6)
        return ntohs(reinterpret_cast<const sockaddr_in6*>(&addr)->sin6_port);
    return 0;
}

void Endpoint::set_port(std::uint16_t port) noexcept {
    if (addr.ss_family == AF_INET)
        reinterpret_cast<sockaddr_in*>(&addr)->sin_port = htons(port);
    else if (addr.ss_family == AF_INET6)
        reinterpret_cast<sockaddr_in6*>(&addr)->sin6_port = htons(port);
}

std::string Endpoint::to_string() const {
    char host[INET6_ADDRSTRLEN] = {};
    if (addr.ss_family == AF_INET) {
        inet_ntop(AF_INET, &reinterpret_cast<const sockaddr_in*>(&addr)->sin_addr, host,
                  sizeof host);
        return std::string(host) + ":" + std::to_string(port());
    }
    if (addr.ss_family == AF_INET6) {
        inet_ntop(AF_INET6, &reinterpret_cast<const sockaddr_in6*>(&addr)->sin6_addr, host,
                  sizeof host);
        return "[" + std::string(host) + "]:" + std::to_string(port());
    }
    return "<unset>";
}

namespace {

bool parse_port(std::string_view text, std::uint16_t& port) {
    unsigned value = 0;
    auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
    if (ec != std::errc() || ptr != text.data() + text.size() || value > 65535 || text.empty())
        return false;
    port = static_cast<std::uint16_t>(value);
    return true;
}

Error resolve_host(const std::string& host, std::uint16_t port, Endpoint& out) {
    out = Endpoint{};
    if (host.empty() || host == "*") {
        auto* in = reinterpret_cast<sockaddr_in*>(&out.addr);
        in->sin_family = AF_INET;
        in->sin_addr.s_addr = htonl(INADDR_ANY);
        out.len = sizeof(sockaddr_in);
        out.set_port(port);
        return Error::none();
    }
    auto* in = reinterpret_cast<sockaddr_in*>(&out.addr);
    if (inet_pton(AF_INET, host.c_str(), &in->sin_addr) == 1) {
        in->sin_family = AF_INET;
        out.len = sizeof(sockaddr_in);
        out.set_port(port);
        return Error::none();
    }
    auto* in6 = reinterpret_cast<sockaddr_in6*>(&out.addr);
    if (inet_pton(AF_INET6, host.c_str(), &in6->sin6_addr) == 1) {
        in6->sin6_family = AF_INET6;
        out.len = sizeof(sockaddr_in6);
        out.set_port(port);
        return Error::none();
    }
    addrinfo hints{};
    hints.ai_family = AF_UNSPEC;
    hints.ai_socktype = SOCK_STREAM;
    addrinfo* result = nullptr;
    int rc = getaddrinfo(host.c_str(), nullptr, &hints, &result);
    if (rc != 0 || !result)
        return Error(ErrorCode::Network, "cannot resolve host '" + host + "': " + gai_strerror(rc));
    std::memcpy(&out.addr, result->ai_addr, result->ai_addrlen);
    out.len = static_cast<socklen_t>(result->ai_addrlen);
    out.set_port(port);
    freeaddrinfo(result);
    return Error::none();
}

}  // namespace

Error split_host_port(std::string_view text, std::string& host, std::uint16_t& port) {
    auto bad_port = [text] {
        return Error(ErrorCode::InvalidInput, "bad port in '" + std::string(text) + "' (0..65535)");
    };
    if (!text.empty() && text.front() == '[') {
        const auto close = text.find(']');
        if (close == std::string_view::npos)
            return Error(ErrorCode::InvalidInput, "missing ']' in '" + std::string(text) + "'");
        const auto rest = text.substr(close + 1);
        if (!rest.empty() && (rest.front() != ':' || !parse_port(rest.substr(1), port)))
            return bad_port();
        host = std::string(text.substr(1, close - 1));
        return Error::none();
    }
    const auto colon = text.find(':');
    if (colon != std::string_view::npos && text.rfind(':') == colon) {
        if (!parse_port(text.substr(colon + 1), port)) return bad_port();
        host = std::string(text.substr(0, colon));
        return Error::none();
    }
    host = std::string(text);  // no port, or a bare IPv6 literal
    return Error::none();
}

Result<Endpoint> parse_endpoint(std::string_view text, std::uint16_t default_port) {
    std::string host;
    std::uint16_t port = default_port;
    if (Error bad = split_host_port(text, host, port); !bad.ok()) return bad;
    Endpoint out;
    if (Error bad = resolve_host(host, port, out); !bad.ok()) return bad;
    return out;
}

Result<UniqueFd> listen_socket(const Endpoint& ep, const ListenOptions& options) {
    int type = SOCK_STREAM | SOCK_CLOEXEC | (options.nonblocking ? SOCK_NONBLOCK : 0);
    UniqueFd fd(::socket(ep.family(), type, 0));
    if (!fd.valid()) return from_errno(ErrorCode::Network, errno, "");
    int one = 1;
    if (setsockopt(fd.get(), SOL_SOCKET, SO_REUSEADDR, &one, sizeof one) != 0 ||
        (options.reuse_port &&
         setsockopt(fd.get(), SOL_SOCKET, SO_REUSEPORT, &one, sizeof one) != 0) ||
        ::bind(fd.get(), ep.sa(), ep.len) != 0 || ::listen(fd.get(), options.backlog) != 0)
        return from_errno(ErrorCode::Network, errno, "");
    return fd;
}

int connect_nonblocking(const Endpoint& ep) noexcept {
    int fd = ::socket(ep.family(), SOCK_STREAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
    if (fd < 0) return -errno;
    if (::connect(fd, ep.sa(), ep.len) != 0 && errno != EINPROGRESS) {
        int e = errno;
        ::close(fd);
        return -e;
    }
    return fd;
}

int connect_blocking(const Endpoint& ep) noexcept {
    int fd = ::socket(ep.family(), SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (fd < 0) return -errno;
    int rc;
    do {
        rc = ::connect(fd, ep.sa(), ep.len);
    } while (rc != 0 && errno == EINTR);
    if (rc != 0) {
        int e = errno;
        ::close(fd);
        return -e;
    }
    return fd;
}

int connect_within(const Endpoint& ep, int timeout_ms) noexcept {
    const int fd = connect_nonblocking(ep);
    if (fd < 0) return -fd;
    pollfd p{fd, POLLOUT, 0};
    int rc;
    do {
        rc = ::poll(&p, 1, timeout_ms);
    } while (rc < 0 && errno == EINTR);
    const int result = rc < 0 ? errno : rc == 0 ? ETIMEDOUT : socket_error(fd);
    ::close(fd);
    return result;
}

int set_nodelay(int fd, bool on) noexcept {
    int v = on ? 1 : 0;
    return setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &v, sizeof v) == 0 ? 0 : -errno;
}

int set_nonblocking(int fd, bool on) noexcept {
    int flags = fcntl(fd, F_GETFL);
    if (flags < 0) return -errno;
    flags = on ? (flags | O_NONBLOCK) : (flags & ~O_NONBLOCK);
    return fcntl(fd, F_SETFL, flags) == 0 ? 0 : -errno;
}

std::uint16_t local_port(int fd) noexcept {
    Endpoint ep;
    ep.len = sizeof ep.addr;
    if (getsockname(fd, reinterpret_cast<sockaddr*>(&ep.addr), &ep.len) != 0) return 0;
    return ep.port();
}

int socket_error(int fd) noexcept {
    int err = 0;
    socklen_t len = sizeof err;
    if (getsockopt(fd, SOL_SOCKET, SO_ERROR, &err, &len) != 0) return errno;
    return err;
}

std::uint64_t raise_nofile_limit(std::uint64_t wanted, std::string* message) noexcept {
    rlimit lim{};
    if (getrlimit(RLIMIT_NOFILE, &lim) != 0) return 0;
    if (lim.rlim_cur >= wanted) return lim.rlim_cur;
    rlimit want = lim;
    if (lim.rlim_max < wanted) {
        // Raising the hard limit needs CAP_SYS_RESOURCE; try, then settle for the hard limit.
        want.rlim_cur = want.rlim_max = wanted;
        if (setrlimit(RLIMIT_NOFILE, &want) == 0) return wanted;
        want = lim;
    }
    want.rlim_cur = lim.rlim_max < wanted ? lim.rlim_max : wanted;
    if (setrlimit(RLIMIT_NOFILE, &want) != 0) want.rlim_cur = lim.rlim_cur;
    if (want.rlim_cur < wanted && message) {
        try {
            *message = "open-files limit is " + std::to_string(want.rlim_cur) + " but " +
                       std::to_string(wanted) + " are needed; raise it with `ulimit -n " +
                       std::to_string(wanted) + "` (hard limit " + std::to_string(lim.rlim_max) +
                       ", see /etc/security/limits.conf) or run with CAP_SYS_RESOURCE";
        } catch (...) {
        }
    }
    return want.rlim_cur;
}

std::uint64_t nofile_limit() noexcept {
    rlimit lim{};
    return getrlimit(RLIMIT_NOFILE, &lim) == 0 ? lim.rlim_cur : 0;
}

std::uint64_t open_descriptor_count() noexcept {
    DIR* dir = opendir("/proc/self/fd");
    if (dir == nullptr) return 0;
    std::uint64_t count = 0;
    while (const dirent* e = readdir(dir))
        if (e->d_name[0] != '.') ++count;
    closedir(dir);
    return count > 0 ? count - 1 : 0;  // not the directory's own descriptor
}

}  // namespace mbstorm::net
