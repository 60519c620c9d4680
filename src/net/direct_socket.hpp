// Sockets held as io_uring direct descriptors: slots of a ring's registered file table instead
// of entries of the process's descriptor table, so RLIMIT_NOFILE (often 1024 or 20k, and not
// always raisable) does not cap the connections. The kernel caps each ring's table at the
// open-files limit instead: many connections take several rings.
#pragma once

#include <liburing.h>

#include <cstdint>

#include "util/error.hpp"

namespace mbstorm::net {

// The file_index for "any free slot" in io_uring_prep_accept_direct: liburing 2.3 stores the
// index plus one, so IORING_FILE_INDEX_ALLOC itself would wrap to "no slot" (a plain accept).
inline constexpr unsigned kAnySlot = IORING_FILE_INDEX_ALLOC - 1;

// Registers an empty table of `slots` on the ring, or a Refused error with the system's reason
// ("Too many open files" above RLIMIT_NOFILE; the caller adds what it was registering).
Error register_socket_table(io_uring* ring, unsigned slots) noexcept;

// Moves the plain descriptor `fd` into `slot` (replacing what was there) and closes `fd`,
// whatever the outcome: 0 or -errno. A socket made with ::socket() can get its options and
// bind() first, which liburing 2.3 has no operation for.
int install_in_slot(io_uring* ring, unsigned slot, int fd) noexcept;

// Shuts the socket in `slot` down (ending its pending receive) and then empties the slot: the
// close runs even when the shutdown fails (a socket that never connected). Two CQEs, with
// `shutdown_data` and `close_data`; the slot is free once the close has completed.
void prep_shutdown_and_close(io_uring_sqe* shutdown_sqe, io_uring_sqe* close_sqe, unsigned slot,
                             std::uint64_t shutdown_data, std::uint64_t close_data) noexcept;

// Marks an SQE's descriptor as a slot of the ring's table when `direct`.
inline void use_slot_if(io_uring_sqe* sqe, bool direct) noexcept {
    if (direct) sqe->flags |= IOSQE_FIXED_FILE;
}

}  // namespace mbstorm::net
