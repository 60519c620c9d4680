#include "net/peer_queue.hpp"

#include <linux/inet_diag.h>
#include <linux/netlink.h>
#include <linux/sock_diag.h>
#include <linux/sockios.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cstring>

#include "net/socket.hpp"

namespace mbstorm::net {
namespace {

struct DiagRequest {
    nlmsghdr header;
    inet_diag_req_v2 body;
};

// Copies an address and port into a diagnostics socket id field pair (network order kept).
bool put_address(const sockaddr_storage& a, __be32 (&addr)[4], __be16& port) noexcept {
    if (a.ss_family == AF_INET) {
        const auto& in = reinterpret_cast<const sockaddr_in&>(a);
        std::memcpy(addr, &in.sin_addr, sizeof in.sin_addr);
        port = in.sin_port;
        return true;
    }
    if (a.ss_family == AF_INET6) {
        const auto& in6 = reinterpret_cast<const sockaddr_in6&>(a);
        std::memcpy(addr, &in6.sin6_addr, sizeof in6.sin6_addr);
        port = in6.sin6_port;
        return true;
    }
    return false;
}

// The exact-socket request for the peer's end of `fd`: its local address is our peer address.
bool peer_request(int fd, DiagRequest& req) noexcept {
    sockaddr_storage ours{}, theirs{};
    socklen_t ours_len = sizeof ours, theirs_len = sizeof theirs;
    if (::getsockname(fd, reinterpret_cast<sockaddr*>(&ours), &ours_len) != 0 ||
        ::getpeername(fd, reinterpret_cast<sockaddr*>(&theirs), &theirs_len) != 0 ||
        ours.ss_family != theirs.ss_family)
        return false;
    std::memset(&req, 0, sizeof req);
    req.header.nlmsg_len = sizeof req;
    req.header.nlmsg_type = SOCK_DIAG_BY_FAMILY;
    req.header.nlmsg_flags = NLM_F_REQUEST;  // one socket, no dump
    req.body.sdiag_family = static_cast<std::uint8_t>(ours.ss_family);
    req.body.sdiag_protocol = IPPROTO_TCP;
    req.body.idiag_states = ~0u;
    req.body.id.idiag_cookie[0] = INET_DIAG_NOCOOKIE;
    req.body.id.idiag_cookie[1] = INET_DIAG_NOCOOKIE;
    return put_address(theirs, req.body.id.idiag_src, req.body.id.idiag_sport) &&
           put_address(ours, req.body.id.idiag_dst, req.body.id.idiag_dport);
}

// The peer socket's receive queue, or -1.
std::int64_t peer_receive_queue(const DiagRequest& req) noexcept {
    UniqueFd nl(::socket(AF_NETLINK, SOCK_DGRAM | SOCK_CLOEXEC, NETLINK_SOCK_DIAG));
    if (!nl.valid()) return -1;
    sockaddr_nl kernel{};
    kernel.nl_family = AF_NETLINK;
    if (::sendto(nl.get(), &req, sizeof req, 0, reinterpret_cast<sockaddr*>(&kernel),
                 sizeof kernel) != static_cast<ssize_t>(sizeof req))
        return -1;
    alignas(nlmsghdr) char buf[1024];
    const ssize_t n = ::recv(nl.get(), buf, sizeof buf, MSG_DONTWAIT);  // answered in sendto()
    if (n < static_cast<ssize_t>(sizeof(nlmsghdr))) return -1;
    const auto* h = reinterpret_cast<const nlmsghdr*>(buf);
    if (!NLMSG_OK(h, static_cast<unsigned>(n)) || h->nlmsg_type != SOCK_DIAG_BY_FAMILY ||
        h->nlmsg_len < NLMSG_LENGTH(sizeof(inet_diag_msg)))
        return -1;  // NLMSG_ERROR: no such socket here (another host or namespace)
    const auto* msg = static_cast<const inet_diag_msg*>(NLMSG_DATA(h));
    return msg->idiag_rqueue;
}

}  // namespace

std::int64_t bytes_unread_by_peer(int fd) noexcept {
    DiagRequest req;
    if (!peer_request(fd, req)) return -1;
    const std::int64_t unread = peer_receive_queue(req);
    if (unread < 0) return -1;
    int unacknowledged = 0;
    if (::ioctl(fd, SIOCOUTQ, &unacknowledged) != 0) return -1;
    return unread + unacknowledged;
}

}  // namespace mbstorm::net
