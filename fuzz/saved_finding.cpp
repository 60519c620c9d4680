// libFuzzer harness: a finding folder's finding.json as `replay` reads it (a file someone
// handed over, or edited). Read, or refused with a reason; never a number converted into a
// field it does not fit (every number goes through case_json.hpp's whole_number).
#include <sys/mman.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "netfuzz/finding.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    // load_finding takes a path: the input as an anonymous file.
    const int fd = ::memfd_create("finding.json", MFD_CLOEXEC);
    if (fd < 0) return 0;
    if (::write(fd, data, size) != static_cast<ssize_t>(size)) {
        ::close(fd);
        return 0;
    }
    mbstorm::netfuzz::Finding finding;
    std::string error;
    if (!mbstorm::netfuzz::load_finding("/proc/self/fd/" + std::to_string(fd), finding, error) &&
        error.empty())
        std::abort();
    ::close(fd);
    return 0;
}
