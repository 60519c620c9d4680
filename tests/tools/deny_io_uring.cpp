// Runs a command where io_uring is refused, as Docker 25+'s and containerd 2.0's default
// seccomp profiles refuse it: io_uring_setup, io_uring_enter and io_uring_register fail with
// EPERM, every other call is allowed. The filter is inherited by everything the command
// starts (a test script's servers and peers too) and cannot be lifted by it.
//
//   deny_io_uring COMMAND [ARGS...]
//
// A raw BPF filter (no libseccomp needed): the architecture is checked first, so a call made
// through another ABI is refused rather than misread.
#include <linux/audit.h>
#include <linux/filter.h>
#include <linux/seccomp.h>
#include <sys/prctl.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <cerrno>
#include <cstddef>
#include <cstdio>

namespace {

#if defined(__x86_64__)
constexpr unsigned kArch = AUDIT_ARCH_X86_64;
#elif defined(__aarch64__)
constexpr unsigned kArch = AUDIT_ARCH_AARCH64;
#else
#error "deny_io_uring: add this architecture's AUDIT_ARCH_ value"
#endif

int install_filter() {
    sock_filter program[] = {
        BPF_STMT(BPF_LD | BPF_W | BPF_ABS, offsetof(seccomp_data, arch)),
        BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, kArch, 1, 0),
        BPF_STMT(BPF_RET | BPF_K, SECCOMP_RET_ERRNO | EPERM),
        BPF_STMT(BPF_LD | BPF_W | BPF_ABS, offsetof(seccomp_data, nr)),
        BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, __NR_io_uring_setup, 3, 0),
        BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, __NR_io_uring_enter, 2, 0),
        BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, __NR_io_uring_register, 1, 0),
        BPF_STMT(BPF_RET | BPF_K, SECCOMP_RET_ALLOW),
        BPF_STMT(BPF_RET | BPF_K, SECCOMP_RET_ERRNO | EPERM),
    };
    sock_fprog filter{static_cast<unsigned short>(sizeof program / sizeof program[0]), program};
    // Without it only a privileged process may install a filter; with it, nothing the command
    // runs can gain privileges the filter would not bind.
    if (prctl(PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0) != 0) return -errno;
    if (prctl(PR_SET_SECCOMP, SECCOMP_MODE_FILTER, &filter) != 0) return -errno;
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 2) {
        std::fprintf(stderr, "usage: deny_io_uring COMMAND [ARGS...]\n");
        return 2;
    }
    if (install_filter() != 0) {
        std::perror("deny_io_uring: installing the seccomp filter");
        return 2;
    }
    execvp(argv[1], argv + 1);
    std::perror("deny_io_uring: exec");
    return 127;
}
