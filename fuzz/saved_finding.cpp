// libFuzzer harness: a finding folder's finding.json as `replay` reads it (a file someone
// handed over, or edited). Read, or refused with a reason; never a number converted into a
// field it does not fit (every number goes through case_json.hpp's whole_number). A finding
// it accepts, saved again (save_finding) and read back, is the same finding: the same root
// cause key, target, seed, counts, notes, variants and wrong fields, and it saves as the same
// finding.json text.
#include <stdlib.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

#include "netfuzz/finding.hpp"

namespace {

using mbstorm::netfuzz::Finding;

void check(bool ok) {
    if (!ok) std::abort();
}

bool same(const Finding& a, const Finding& b) {
    return a.key() == b.key() && a.target == b.target && a.seed == b.seed &&
           a.case_number == b.case_number && a.minimized == b.minimized &&
           a.confirmed == b.confirmed && a.note == b.note && a.hits == b.hits &&
           a.variants == b.variants && a.minimize_note == b.minimize_note &&
           a.wrong_fields == b.wrong_fields && a.restarts == b.restarts &&
           a.timeout_ms == b.timeout_ms && a.original_steps == b.original_steps;
}

// One scratch folder per process, written over by every save.
const std::string& scratch_dir() {
    static const std::string dir = [] {
        char name[] = "/tmp/fuzz_saved_finding.XXXXXX";
        check(::mkdtemp(name) != nullptr);
        return std::string(name);
    }();
    return dir;
}

// Saves `f` into the scratch folder; returns its finding.json.
std::string save(const Finding& f) {
    const std::string& dir = scratch_dir();
    check(mbstorm::netfuzz::save_finding(f, dir).ok());
    std::ifstream in(dir + "/finding.json");
    std::stringstream text;
    text << in.rdbuf();
    return text.str();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    // load_finding takes a path: the input as an anonymous file.
    const int fd = ::memfd_create("finding.json", MFD_CLOEXEC);
    if (fd < 0) return 0;
    if (::write(fd, data, size) != static_cast<ssize_t>(size)) {
        ::close(fd);
        return 0;
    }
    const mbstorm::Result<Finding> loaded =
        mbstorm::netfuzz::load_finding("/proc/self/fd/" + std::to_string(fd));
    ::close(fd);
    if (!loaded.ok()) {
        check(!loaded.error().message().empty());  // a refusal says why
        return 0;
    }
    const Finding& finding = *loaded;
    const std::string saved = save(finding);
    const mbstorm::Result<Finding> again = mbstorm::netfuzz::load_finding(scratch_dir());
    check(again.ok() && same(finding, *again));
    check(save(*again) == saved);
    return 0;
}
