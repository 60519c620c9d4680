// io_uring_probe: sets up one io_uring with liburing and says what the kernel answered, so the
// seccomp tests can tell "denied by the filter" (EPERM) from "set up" and from "killed".
//   io_uring_probe    prints "io_uring_queue_init: 0" and exits 0, or
//                     "io_uring_queue_init: -ERRNO (message)" and exits 1.
#include <liburing.h>

#include <cstdio>
#include <cstring>

int main() {
    io_uring ring{};
    int rc = io_uring_queue_init(8, &ring, 0);
    if (rc < 0) {
        std::printf("io_uring_queue_init: -%d (%s)\n", -rc, std::strerror(-rc));
        return 1;
    }
    // A round trip through io_uring_enter too: a filter that allowed only the setup call
    // would still leave the ring useless.
    io_uring_sqe* sqe = io_uring_get_sqe(&ring);
    io_uring_prep_nop(sqe);
    rc = io_uring_submit_and_wait(&ring, 1);
    io_uring_queue_exit(&ring);
    if (rc < 0) {
        std::printf("io_uring_submit_and_wait: -%d (%s)\n", -rc, std::strerror(-rc));
        return 1;
    }
    std::printf("io_uring_queue_init: 0\n");
    return 0;
}
