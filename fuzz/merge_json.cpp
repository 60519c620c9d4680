// libFuzzer harness: a shard's JSON summary as `merge` reads it (from the shards of a
// distributed test: files the user did not write by hand). Read, or refused with a reason
// naming the file. A summary it accepts keeps every per-operation and per-stage extreme beside
// its operation or stage (merge_shards indexes them together), and reading the file again
// gives the same summary (counts, operations, extremes, thresholds).
#include <sys/mman.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "report/merge.hpp"

namespace {

using mbstorm::report::ShardRun;

void check(bool ok) {
    if (!ok) std::abort();
}

bool same(const ShardRun& a, const ShardRun& b) {
    const auto &x = a.summary, &y = b.summary;
    bool ok = x.counters.completed() == y.counters.completed() &&
              x.operations.size() == y.operations.size() && x.stages.size() == y.stages.size() &&
              x.timeline.size() == y.timeline.size();
    for (std::size_t i = 0; ok && i < x.operations.size(); ++i)
        ok = x.operations[i].name == y.operations[i].name &&
             x.operations[i].counters.completed() == y.operations[i].counters.completed();
    return ok && a.min_ns == b.min_ns && a.max_ns == b.max_ns &&
           a.latency_count == b.latency_count && a.op_min_ns == b.op_min_ns &&
           a.op_max_ns == b.op_max_ns && a.stage_min_ns == b.stage_min_ns &&
           a.stage_max_ns == b.stage_max_ns && a.threshold_expressions == b.threshold_expressions;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    // read_shard_summary takes a path: the input as an anonymous file.
    const int fd = ::memfd_create("shard.json", MFD_CLOEXEC);
    if (fd < 0) return 0;
    if (::write(fd, data, size) != static_cast<ssize_t>(size)) {
        ::close(fd);
        return 0;
    }
    const std::string path = "/proc/self/fd/" + std::to_string(fd);
    ShardRun run, again;
    if (const mbstorm::Error error = mbstorm::report::read_shard_summary(path, run); !error.ok()) {
        check(error.text().find(path) != std::string::npos);  // the refusal names the file
        ::close(fd);
        return 0;
    }
    const std::size_t ops = run.summary.operations.size(), stages = run.summary.stages.size();
    check(run.op_min_ns.size() == ops && run.op_max_ns.size() == ops);
    check(run.stage_min_ns.size() == stages && run.stage_max_ns.size() == stages);
    check(mbstorm::report::read_shard_summary(path, again).ok() && same(run, again));
    ::close(fd);
    return 0;
}
