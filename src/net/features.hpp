// What the running kernel's io_uring can do, found by trying (not by version numbers), once
// per process. Everything above net/ asks here and takes the fallback path when a flag is off.
#pragma once

#include <cstdio>
#include <string>
#include <string_view>
#include <vector>

namespace mbstorm::net {

struct Features {
    bool ring = false;              // io_uring_queue_init works at all (not blocked by seccomp)
    int ring_errno = 0;             // why not: EPERM (seccomp, sysctl), ENOSYS (no io_uring)
    bool single_issuer = false;     // IORING_SETUP_SINGLE_ISSUER (6.0)
    bool defer_taskrun = false;     // IORING_SETUP_DEFER_TASKRUN (6.1, needs single_issuer)
    bool coop_taskrun = false;      // IORING_SETUP_COOP_TASKRUN (5.19)
    bool multishot_accept = false;  // IORING_ACCEPT_MULTISHOT (5.19)
    bool multishot_recv = false;    // IORING_RECV_MULTISHOT (6.0)
    bool buf_ring = false;          // IORING_REGISTER_PBUF_RING (5.19)
    bool send_zc = false;           // IORING_OP_SEND_ZC (6.0)
    // Sockets as direct descriptors: a sparse registered file table, accept into a slot the
    // kernel allocates (IORING_FILE_INDEX_ALLOC), shutdown and close of a slot (5.19).
    bool direct_descriptors = false;
    std::string kernel;  // uname release, for reports
};

// Probes on first call (thread-safe), cached afterwards.
const Features& features() noexcept;

// Probes afresh (creates and destroys a few temporary rings and sockets).
Features probe_features() noexcept;

// Each optional feature by the name reports use for it ("multishot_accept", ...), in a fixed
// order, with whether `f` has it.
struct NamedFeature {
    std::string_view name;
    bool offered;
};
std::vector<NamedFeature> named_features(const Features& f);

// One line, e.g. "io_uring on 6.1.0: multishot_accept=yes multishot_recv=yes ...".
std::string describe(const Features& f);
void print_features(const Features& f, std::FILE* out);

}  // namespace mbstorm::net
