#include "net/direct_socket.hpp"

#include <sys/socket.h>
#include <unistd.h>

namespace mbstorm::net {

Error register_socket_table(io_uring* ring, unsigned slots) noexcept {
    const int rc = io_uring_register_files_sparse(ring, slots);
    if (rc >= 0) return {};
    return from_errno(ErrorCode::Refused, -rc, "");
}

int install_in_slot(io_uring* ring, unsigned slot, int fd) noexcept {
    const int rc = io_uring_register_files_update(ring, slot, &fd, 1);
    ::close(fd);
    return rc < 0 ? rc : 0;
}

void prep_shutdown_and_close(io_uring_sqe* shutdown_sqe, io_uring_sqe* close_sqe, unsigned slot,
                             std::uint64_t shutdown_data, std::uint64_t close_data) noexcept {
    io_uring_prep_shutdown(shutdown_sqe, static_cast<int>(slot), SHUT_RDWR);
    shutdown_sqe->flags |= IOSQE_FIXED_FILE | IOSQE_IO_HARDLINK;
    io_uring_sqe_set_data64(shutdown_sqe, shutdown_data);
    io_uring_prep_close_direct(close_sqe, slot);
    io_uring_sqe_set_data64(close_sqe, close_data);
}

}  // namespace mbstorm::net
