#include "report/timeline_stream.hpp"

#include <cerrno>
#include <cstring>

#include "report/files.hpp"
#include "report/interval_json.hpp"

namespace mbstorm::report {

std::string format_timeline_line(const stats::IntervalSummary& interval,
                                 std::chrono::system_clock::time_point measure_start,
                                 const std::string& test_id, const std::string& run_id) {
    nlohmann::json line = interval_json(interval);
    line["duration_s"] = static_cast<double>(interval.duration_ns) / 1e9;
    const double start_epoch_s =
        std::chrono::duration<double>(measure_start.time_since_epoch()).count();
    line["epoch_s"] = start_epoch_s + static_cast<double>(interval.start_offset_ns) / 1e9;
    line["test"] = test_id;
    line["run_id"] = run_id;
    return line.dump() + "\n";
}

TimelineWriter::~TimelineWriter() {
    if (file_ != nullptr) std::fclose(file_);
}

Error TimelineWriter::open(const std::string& path, std::string test_id, std::string run_id) {
    file_ = std::fopen(path.c_str(), "w");
    if (file_ == nullptr) return from_errno(ErrorCode::Io, errno, path);
    test_id_ = std::move(test_id);
    run_id_ = std::move(run_id);
    return Error::none();
}

void TimelineWriter::write(const stats::IntervalSummary& interval,
                           std::chrono::system_clock::time_point measure_start) {
    if (file_ == nullptr) return;
    const std::string line = format_timeline_line(interval, measure_start, test_id_, run_id_);
    if (std::fputs(line.c_str(), file_) < 0 || std::fflush(file_) != 0) failed_ = true;
}

Error TimelineWriter::close() {
    return close_streamed_file(file_, failed_);
}

}  // namespace mbstorm::report
