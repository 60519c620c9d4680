// libFuzzer harness: a shard's JSON summary as `merge` reads it (from the shards of a
// distributed test: files the user did not write by hand). Read, or refused with a reason.
#include <sys/mman.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "report/merge.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    // read_shard_summary takes a path: the input as an anonymous file.
    const int fd = ::memfd_create("shard.json", MFD_CLOEXEC);
    if (fd < 0) return 0;
    if (::write(fd, data, size) != static_cast<ssize_t>(size)) {
        ::close(fd);
        return 0;
    }
    mbstorm::report::ShardRun run;
    std::string error;
    if (!mbstorm::report::read_shard_summary("/proc/self/fd/" + std::to_string(fd), run, error) &&
        error.empty())
        std::abort();
    ::close(fd);
    return 0;
}
