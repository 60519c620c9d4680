#include "net/backend.hpp"

#include <cerrno>
#include <cstring>

#include "net/features.hpp"

namespace mbstorm::net {

std::string_view backend_name(Backend backend) noexcept {
    switch (backend) {
        case Backend::IoUring:
            return "io_uring";
        case Backend::Epoll:
            return "epoll";
    }
    return "?";
}

bool parse_backend_choice(std::string_view text, BackendChoice& choice) noexcept {
    if (text == "auto") {
        choice = BackendChoice::Auto;
    } else if (text == "io_uring") {
        choice = BackendChoice::IoUring;
    } else if (text == "epoll") {
        choice = BackendChoice::Epoll;
    } else {
        return false;
    }
    return true;
}

namespace {

// Why io_uring cannot be used here, or "" when it can.
std::string io_uring_unusable(bool need_buf_ring) {
    const Features& f = features();
    if (!f.ring) {
        const int e = f.ring_errno;
        std::string why = "io_uring_setup refused (" + std::string(std::strerror(e)) + ")";
        if (e == EPERM || e == EACCES)
            why +=
                ": a seccomp profile such as Docker's or containerd's default, or "
                "kernel.io_uring_disabled";
        // podman's default profile answers ENOSYS where Docker's answers EPERM.
        if (e == ENOSYS)
            why += ": a kernel without io_uring, or a seccomp profile (podman's default)";
        return why;
    }
    if (need_buf_ring && !f.buf_ring)
        return "the kernel (" + f.kernel + ") lacks io_uring provided buffer rings (5.19+)";
    return "";
}

}  // namespace

Result<BackendDecision> choose_backend(BackendChoice choice, bool need_buf_ring) {
    BackendDecision decision;
    switch (choice) {
        case BackendChoice::Epoll:
            decision.backend = Backend::Epoll;
            return decision;
        case BackendChoice::IoUring:
            if (std::string why = io_uring_unusable(need_buf_ring); !why.empty())
                return Error(ErrorCode::Unsupported, "--backend io_uring: " + why);
            return decision;
        case BackendChoice::Auto:
            decision.why = io_uring_unusable(need_buf_ring);
            decision.backend = decision.why.empty() ? Backend::IoUring : Backend::Epoll;
            return decision;
    }
    return Error(ErrorCode::InvalidInput, "unknown backend choice");
}

}  // namespace mbstorm::net
