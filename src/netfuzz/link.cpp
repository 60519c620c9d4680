#include "netfuzz/link.hpp"

#include <poll.h>
#include <sys/socket.h>

#include <cerrno>

#include "net/peer_queue.hpp"
#include "netfuzz/executor.hpp"

namespace mbstorm::netfuzz {

ssize_t TcpLink::send(const std::uint8_t* data, std::size_t size) noexcept {
    for (;;) {
        const ssize_t n = ::send(fd_.get(), data, size, MSG_NOSIGNAL);
        if (n >= 0) return n;
        if (errno == EINTR) continue;
        return errno == EWOULDBLOCK ? -EAGAIN : -errno;
    }
}

ssize_t TcpLink::recv(std::uint8_t* data, std::size_t size) noexcept {
    for (;;) {
        const ssize_t n = ::recv(fd_.get(), data, size, 0);
        if (n >= 0) return n;
        if (errno == EINTR) continue;
        return errno == EWOULDBLOCK ? -EAGAIN : -errno;
    }
}

void TcpLink::shutdown_write() noexcept {
    ::shutdown(fd_.get(), SHUT_WR);
}

std::int64_t TcpLink::unread_by_target() const noexcept {
    return net::bytes_unread_by_peer(fd_.get());
}

std::unique_ptr<Link> TcpConnector::open(int timeout_ms, int& error) {
    const int fd = connect_with_timeout(target_, timeout_ms);
    if (fd < 0) {
        error = -fd;
        return nullptr;
    }
    error = 0;
    return std::make_unique<TcpLink>(net::UniqueFd(fd));
}

bool wait_readable(const Link& link, int timeout_ms) noexcept {
    if (link.has_buffered_input()) return true;
    pollfd p{link.poll_fd(), POLLIN, 0};
    int rc;
    do {
        rc = ::poll(&p, 1, timeout_ms);
    } while (rc < 0 && errno == EINTR);
    return rc > 0;
}

}  // namespace mbstorm::netfuzz
