#include "net/features.hpp"

#include <liburing.h>
#include <sys/socket.h>
#include <sys/utsname.h>
#include <unistd.h>

#include "net/buf_ring.hpp"
#include "net/direct_socket.hpp"
#include "net/ring.hpp"
#include "net/socket.hpp"

namespace mbstorm::net {

namespace {

bool ring_accepts_flags(unsigned flags) {
    io_uring ring{};
    io_uring_params params{};
    params.flags = flags;
    if (io_uring_queue_init_params(8, &ring, &params) != 0) return false;
    io_uring_queue_exit(&ring);
    return true;
}

// Waits at most one second for a CQE so that a misbehaving kernel cannot hang the probe.
bool wait_one(io_uring* ring, io_uring_cqe** cqe) {
    __kernel_timespec ts{};
    ts.tv_sec = 1;
    return io_uring_wait_cqe_timeout(ring, cqe, &ts) == 0;
}

bool probe_multishot_recv(io_uring* ring, std::uint16_t group) {
    int sv[2];
    if (socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, sv) != 0) return false;
    UniqueFd a(sv[0]), b(sv[1]);
    const char byte = 'x';
    if (::write(b.get(), &byte, 1) != 1) return false;
    io_uring_sqe* sqe = io_uring_get_sqe(ring);
    io_uring_prep_recv_multishot(sqe, a.get(), nullptr, 0, 0);
    sqe->flags |= IOSQE_BUFFER_SELECT;
    sqe->buf_group = group;
    io_uring_submit(ring);
    io_uring_cqe* cqe = nullptr;
    if (!wait_one(ring, &cqe)) return false;
    bool ok = cqe->res == 1 && (cqe->flags & IORING_CQE_F_MORE);
    io_uring_cqe_seen(ring, cqe);
    return ok;
}

// A listener on an ephemeral loopback port, `ep` set to its address; not valid when the
// process cannot listen.
UniqueFd loopback_listener(Endpoint& ep) {
    Result<Endpoint> loopback = parse_endpoint("127.0.0.1:0");
    if (!loopback.ok()) return UniqueFd();
    ep = *loopback;
    Result<UniqueFd> listener = listen_socket(ep, ListenOptions{16, false, true});
    if (!listener.ok()) return UniqueFd();
    ep.set_port(local_port(listener->get()));
    return std::move(listener).value();
}

bool probe_multishot_accept(io_uring* ring) {
    Endpoint ep;
    const UniqueFd listener = loopback_listener(ep);
    if (!listener.valid()) return false;
    io_uring_sqe* sqe = io_uring_get_sqe(ring);
    io_uring_prep_multishot_accept(sqe, listener.get(), nullptr, nullptr, SOCK_CLOEXEC);
    io_uring_submit(ring);
    UniqueFd client(connect_blocking(ep));
    if (!client.valid()) return false;
    io_uring_cqe* cqe = nullptr;
    if (!wait_one(ring, &cqe)) return false;
    bool ok = cqe->res >= 0 && (cqe->flags & IORING_CQE_F_MORE);
    if (cqe->res >= 0) ::close(cqe->res);
    io_uring_cqe_seen(ring, cqe);
    return ok;
}

// Accepts one connection into a slot the kernel allocates, then shuts it down and closes the
// slot the way the workers do.
bool probe_direct_descriptors(io_uring* ring) {
    if (!register_socket_table(ring, 4).ok()) return false;
    Endpoint ep;
    const UniqueFd listener = loopback_listener(ep);
    if (!listener.valid()) return false;
    io_uring_sqe* sqe = io_uring_get_sqe(ring);
    io_uring_prep_accept_direct(sqe, listener.get(), nullptr, nullptr, 0, kAnySlot);
    io_uring_submit(ring);
    UniqueFd client(connect_blocking(ep));
    if (!client.valid()) return false;
    io_uring_cqe* cqe = nullptr;
    if (!wait_one(ring, &cqe)) return false;
    const int slot = cqe->res;
    io_uring_cqe_seen(ring, cqe);
    if (slot < 0 || slot >= 4) return false;
    prep_shutdown_and_close(io_uring_get_sqe(ring), io_uring_get_sqe(ring),
                            static_cast<unsigned>(slot), 1, 2);
    io_uring_submit(ring);
    bool closed = false;
    for (int i = 0; i < 2 && wait_one(ring, &cqe); ++i) {
        if (cqe->user_data == 2) closed = cqe->res == 0;
        io_uring_cqe_seen(ring, cqe);
    }
    return closed;
}

}  // namespace

Features probe_features() noexcept {
    Features f;
    try {
        utsname u{};
        if (uname(&u) == 0) f.kernel = u.release;
    } catch (...) {
    }
    Ring ring;
    RingOptions plain;
    plain.entries = 16;
    plain.single_issuer = plain.defer_taskrun = plain.coop_taskrun = false;
    if (const int rc = ring.init(plain); rc != 0) {
        f.ring_errno = -rc;
        return f;
    }
    f.ring = true;
    f.single_issuer = ring_accepts_flags(IORING_SETUP_SINGLE_ISSUER);
    f.defer_taskrun = ring_accepts_flags(IORING_SETUP_SINGLE_ISSUER | IORING_SETUP_DEFER_TASKRUN);
    f.coop_taskrun = ring_accepts_flags(IORING_SETUP_COOP_TASKRUN | IORING_SETUP_TASKRUN_FLAG);
    if (io_uring_probe* p = io_uring_get_probe_ring(ring.get())) {
        f.send_zc = io_uring_opcode_supported(p, IORING_OP_SEND_ZC);
        io_uring_free_probe(p);
    }
    {
        BufRing br;
        f.buf_ring = br.init(ring.get(), 7, 8, 64) == 0;
        if (f.buf_ring) f.multishot_recv = probe_multishot_recv(ring.get(), 7);
    }
    {
        // A fresh ring: the recv probe above leaves a completion behind when its sockets close.
        Ring accept_ring;
        if (accept_ring.init(plain) == 0)
            f.multishot_accept = probe_multishot_accept(accept_ring.get());
    }
    {
        Ring direct_ring;
        if (direct_ring.init(plain) == 0)
            f.direct_descriptors = probe_direct_descriptors(direct_ring.get());
    }
    return f;
}

const Features& features() noexcept {
    static const Features cached = probe_features();
    return cached;
}

std::vector<NamedFeature> named_features(const Features& f) {
    return {{"multishot_accept", f.multishot_accept},
            {"multishot_recv", f.multishot_recv},
            {"buf_ring", f.buf_ring},
            {"send_zc", f.send_zc},
            {"direct_descriptors", f.direct_descriptors},
            {"single_issuer", f.single_issuer},
            {"defer_taskrun", f.defer_taskrun},
            {"coop_taskrun", f.coop_taskrun}};
}

std::string describe(const Features& f) {
    std::string s = "io_uring on " + (f.kernel.empty() ? std::string("?") : f.kernel) + ": ";
    if (!f.ring) return s + "unavailable";
    const char* separator = "";
    for (const NamedFeature& feature : named_features(f)) {
        s.append(separator).append(feature.name).append(feature.offered ? "=yes" : "=no");
        separator = " ";
    }
    return s;
}

void print_features(const Features& f, std::FILE* out) {
    std::fprintf(out, "%s\n", describe(f).c_str());
}

}  // namespace mbstorm::net
