#include "net/kernel_tls.hpp"

#include <netinet/in.h>
#include <netinet/tcp.h>
#include <sys/socket.h>

#include <atomic>
#include <cerrno>
#include <cstring>

#include "net/socket.hpp"

namespace mbstorm::net {
namespace {

KernelTls probe() {
    KernelTls k;
    // The upper-layer protocol attaches only to an established connection.
    UniqueFd listener(::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0));
    UniqueFd client(::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0));
    if (!listener.valid() || !client.valid()) {
        k.detail = std::string("no socket for the probe: ") + std::strerror(errno);
        return k;
    }
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t len = sizeof a;
    if (::bind(listener.get(), reinterpret_cast<sockaddr*>(&a), sizeof a) != 0 ||
        ::listen(listener.get(), 1) != 0 ||
        ::getsockname(listener.get(), reinterpret_cast<sockaddr*>(&a), &len) != 0 ||
        ::connect(client.get(), reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
        k.detail = std::string("no loopback connection for the probe: ") + std::strerror(errno);
        return k;
    }
    UniqueFd accepted(::accept4(listener.get(), nullptr, nullptr, SOCK_CLOEXEC));
    static constexpr char kUlp[] = "tls";
    if (::setsockopt(client.get(), SOL_TCP, TCP_ULP, kUlp, sizeof kUlp - 1) != 0) {
        k.detail = std::string("TCP_ULP tls: ") + std::strerror(errno);
        return k;
    }
    k.available = true;
    return k;
}

std::atomic<bool> pretend_available{false};

}  // namespace

const KernelTls& kernel_tls() noexcept {
    static const KernelTls k = probe();
    static const KernelTls pretended{true, "pretended by a test"};
    return pretend_available.load(std::memory_order_relaxed) ? pretended : k;
}

void pretend_kernel_tls_for_testing(bool available) noexcept {
    pretend_available.store(available, std::memory_order_relaxed);
}

std::string describe_tls_path() {
    const KernelTls& k = kernel_tls();
    if (k.available)
        return "TLS records encrypted by OpenSSL in userspace over io_uring until each "
               "handshake ends, then by the kernel's TLS offload on the connections it can take "
               "(counted as offloaded)";
    return "TLS records encrypted by OpenSSL in userspace over io_uring (no kernel TLS offload "
           "here: " +
           k.detail + ")";
}

}  // namespace mbstorm::net
