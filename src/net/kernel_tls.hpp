// Whether the kernel offers TLS offload (kTLS: the "tls" upper-layer protocol on a TCP
// socket), found by trying it once per process on a loopback connection. With it, the
// record layer could move into the kernel after the handshake and io_uring would carry
// plaintext (ktls_offload.hpp does the hand-off); without it (this project's CI kernel has no
// tls module), OpenSSL encrypts in userspace over io_uring throughout.
#pragma once

#include <string>

namespace mbstorm::net {

struct KernelTls {
    bool available = false;
    std::string detail;  // why not (e.g. "TCP_ULP tls: No such file or directory")
};

// Probes on first call (thread-safe), cached afterwards.
const KernelTls& kernel_tls() noexcept;

// Tests only: kernel_tls() says available (true) or the probe's answer again (false), so the
// hand-off's hooks run on a kernel without the offload (with a fake install_ktls).
void pretend_kernel_tls_for_testing(bool available) noexcept;

// One sentence for reports: how TLS records are encrypted in this process, and why.
std::string describe_tls_path();

}  // namespace mbstorm::net
