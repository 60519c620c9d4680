#include "report/hlog.hpp"

#include <fmt/chrono.h>
#include <fmt/format.h>

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <fstream>
#include <sstream>

#include "report/files.hpp"
#include "stats/hdr_encoding.hpp"

namespace mbstorm::report {
namespace {

constexpr std::string_view kFormatVersionLine = "[Histogram log format version 1.3]";
constexpr std::string_view kLegend =
    "\"StartTimestamp\",\"Interval_Length\",\"Interval_Max\",\"Interval_Compressed_Histogram\"";

double epoch_seconds(std::chrono::system_clock::time_point t) {
    return std::chrono::duration<double>(t.time_since_epoch()).count();
}

// Parses the whole field as a finite number.
bool parse_double(std::string_view text, double& out) {
    if (text.empty()) return false;
    const std::string copy(text);
    char* end = nullptr;
    errno = 0;
    out = std::strtod(copy.c_str(), &end);
    return end == copy.c_str() + copy.size() && errno == 0 && std::isfinite(out);
}

// "#[StartTime: 1795942311.123 (seconds ..." -> the number after the key.
bool header_number(std::string_view comment, std::string_view key, double& out) {
    if (comment.substr(0, key.size()) != key) return false;
    std::string_view rest = comment.substr(key.size());
    while (!rest.empty() && rest.front() == ' ') rest.remove_prefix(1);
    const auto end = rest.find_first_of(" ]");
    return parse_double(rest.substr(0, end), out);
}

}  // namespace

std::string hlog_tag(std::string_view name) {
    std::string tag(name);
    for (char& c : tag)
        if (c == ',' || c == ' ' || c == '\t' || c == '\r' || c == '\n') c = '_';
    return tag;
}

namespace {
constexpr std::string_view kStageTagPrefix = "stage:";
}

std::string hlog_stage_tag(std::uint32_t stage_index) {
    return fmt::format("{}{}", kStageTagPrefix, stage_index);
}

std::uint32_t stage_of_hlog_tag(std::string_view tag) {
    if (tag.substr(0, kStageTagPrefix.size()) != kStageTagPrefix) return 0;
    tag.remove_prefix(kStageTagPrefix.size());
    std::uint32_t index = 0;
    const auto [end, ec] = std::from_chars(tag.data(), tag.data() + tag.size(), index);
    return ec == std::errc() && end == tag.data() + tag.size() ? index : 0;
}

std::string hlog_identity_text(const HlogIdentity& identity) {
    std::string text =
        fmt::format("mbstorm interval log: test {}, run {}",
                    identity.test_id.empty() ? "-" : identity.test_id, identity.run_id);
    if (identity.shard_count != 0)
        text += fmt::format(", shard {}/{}", identity.shard_index, identity.shard_count);
    return text;
}

bool find_hlog_identity(const Hlog& log, HlogIdentity& out) {
    constexpr std::string_view kLead = "mbstorm interval log: test ";
    for (const auto& c : log.comments) {
        const auto at = c.find(kLead);
        const auto run = c.rfind(", run ");
        if (at == std::string::npos || run == std::string::npos || run < at + kLead.size())
            continue;
        HlogIdentity id;
        id.test_id = c.substr(at + kLead.size(), run - at - kLead.size());
        std::string rest = c.substr(run + 6);
        if (!rest.empty() && rest.back() == ']') rest.pop_back();
        if (const auto shard = rest.find(", shard "); shard != std::string::npos) {
            unsigned index = 0, count = 0;
            char slash = 0;
            std::istringstream in(rest.substr(shard + 8));
            if (!(in >> index >> slash >> count) || slash != '/') continue;
            id.shard_index = index;
            id.shard_count = count;
            rest.resize(shard);
        }
        id.run_id = rest;
        out = id;
        return true;
    }
    return false;
}

HlogWriter::~HlogWriter() {
    if (file_ != nullptr) std::fclose(file_);
}

Error HlogWriter::open(const std::string& path, std::string comment) {
    file_ = std::fopen(path.c_str(), "w");
    if (file_ == nullptr) return from_errno(ErrorCode::Io, errno, path);
    comment_ = std::move(comment);
    return Error::none();
}

void HlogWriter::start(std::chrono::system_clock::time_point start_time) {
    if (file_ == nullptr || started_) return;
    started_ = true;
    const double start = epoch_seconds(start_time);
    const std::time_t seconds = std::chrono::system_clock::to_time_t(start_time);
    std::tm tm{};
    gmtime_r(&seconds, &tm);
    // The date as HdrHistogram's Java writer prints it (Date.toString(), here in UTC).
    const std::string date = fmt::format("{:%a %b %d %H:%M:%S} UTC {:%Y}", tm, tm);
    std::string head;
    if (!comment_.empty()) head += fmt::format("#[{}]\n", comment_);
    head += fmt::format("#{}\n", kFormatVersionLine);
    head += fmt::format("#[StartTime: {:.3f} (seconds since epoch), {}]\n", start, date);
    // Line times are relative: the base time is the start time.
    head += fmt::format("#[BaseTime: {:.3f} (seconds since epoch)]\n", start);
    head += fmt::format("{}\n", kLegend);
    if (std::fputs(head.c_str(), file_) < 0) failed_ = true;
}

void HlogWriter::write_interval(std::string_view tag, double start_s, double length_s,
                                const stats::Histogram& histogram) {
    if (file_ == nullptr) return;
    const std::string line =
        fmt::format("{}{:.3f},{:.3f},{:.3f},{}\n", tag.empty() ? "" : fmt::format("Tag={},", tag),
                    start_s, length_s, static_cast<double>(histogram.max()) / 1e6,
                    stats::encode_hdr_compressed_base64(histogram));
    if (std::fputs(line.c_str(), file_) < 0) failed_ = true;
}

void HlogWriter::end_interval() {
    if (file_ != nullptr && std::fflush(file_) != 0) failed_ = true;
}

Error HlogWriter::close() {
    if (file_ == nullptr) return Error::none();
    if (!started_) start(std::chrono::system_clock::now());
    return close_streamed_file(file_, failed_);
}

double Hlog::absolute_start_s(const HlogInterval& interval) const {
    // HdrHistogram's rule: without a base time, timestamps more than a year before the start
    // time are relative to it.
    double base = base_time_s;
    if (!has_base_time) {
        const double first = intervals.empty() ? interval.start_s : intervals.front().start_s;
        base = has_start_time && first < start_time_s - 365 * 24 * 3600.0 ? start_time_s : 0.0;
    }
    return interval.start_s + base;
}

namespace {

bool refuse_line(std::string& why, const char* text) {
    why = text;
    return false;
}

// One line of a log: a header comment (into header), a legend (skipped) or an interval (into
// interval, decoded; `is_interval` set). False with `why` when the line is neither.
bool parse_hlog_line(std::string_view line, Hlog& header, HlogInterval& interval, bool& is_interval,
                     std::string& why) {
    is_interval = false;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    if (line.empty()) return true;
    if (line.front() == '#') {
        const std::string_view comment = line.substr(1);
        header.comments.emplace_back(comment);
        double value = 0;
        if (header_number(comment, "[StartTime:", value)) {
            header.has_start_time = true;
            header.start_time_s = value;
        } else if (header_number(comment, "[BaseTime:", value)) {
            header.has_base_time = true;
            header.base_time_s = value;
        }
        return true;
    }
    if (line.front() == '"' || line.substr(0, 9) == "StartTime" || line.substr(0, 9) == "Timestamp")
        return true;  // a legend
    interval.tag.clear();
    if (line.substr(0, 4) == "Tag=") {
        const auto comma = line.find(',');
        if (comma == std::string_view::npos) return refuse_line(why, "a tag and nothing else");
        interval.tag = std::string(line.substr(4, comma - 4));
        line.remove_prefix(comma + 1);
    }
    std::string_view fields[4];
    for (int i = 0; i < 4; ++i) {
        const auto comma = i < 3 ? line.find(',') : std::string_view::npos;
        if (i < 3 && comma == std::string_view::npos)
            return refuse_line(why, "an interval line has four fields: start,length,max,histogram");
        fields[i] = line.substr(0, comma);
        if (i < 3) line.remove_prefix(comma + 1);
    }
    if (!parse_double(fields[0], interval.start_s) || !parse_double(fields[1], interval.length_s) ||
        !parse_double(fields[2], interval.max_ms))
        return refuse_line(why, "start, length and max must be numbers");
    if (interval.length_s < 0) return refuse_line(why, "negative interval length");
    if (Error bad = stats::decode_hdr_compressed_base64(fields[3], interval.histogram); !bad.ok()) {
        why = bad.message();
        return false;
    }
    is_interval = true;
    return true;
}

}  // namespace

HlogReader::HlogReader(std::istream& in) : in_(in) {}

bool HlogReader::next(HlogInterval& out) {
    std::string why;
    while (error_.ok()) {
        line_offset_ = static_cast<std::uint64_t>(in_.tellg());
        if (!std::getline(in_, line_)) return false;
        ++line_number_;
        bool is_interval = false;
        if (!parse_hlog_line(line_, header_, out, is_interval, why))
            error_ = Error(ErrorCode::InvalidInput, fmt::format("line {}: {}", line_number_, why));
        else if (is_interval)
            return true;
    }
    return false;
}

bool HlogReader::read_header() {
    while (error_.ok()) {
        const auto at = in_.tellg();
        if (!std::getline(in_, line_)) return true;
        if (!line_.empty() && line_.front() != '#' && line_.front() != '"' &&
            line_.substr(0, 9) != "StartTime" && line_.substr(0, 9) != "Timestamp") {
            in_.clear();
            in_.seekg(at);
            return true;
        }
        ++line_number_;
        HlogInterval unused;
        bool is_interval = false;
        std::string why;
        if (!parse_hlog_line(line_, header_, unused, is_interval, why))
            error_ = Error(ErrorCode::InvalidInput, fmt::format("line {}: {}", line_number_, why));
    }
    return false;
}

bool HlogReader::read_at(std::uint64_t offset, HlogInterval& out) {
    in_.clear();
    in_.seekg(static_cast<std::streamoff>(offset));
    return next(out);
}

Result<Hlog> parse_hlog(std::string_view text) {
    std::istringstream in{std::string(text)};
    HlogReader reader(in);
    HlogInterval interval;
    while (reader.next(interval)) reader.header().intervals.push_back(interval);
    if (!reader.error().ok()) return reader.error();
    return std::move(reader.header());
}

Result<Hlog> read_hlog(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) return from_errno(ErrorCode::Io, errno, path);
    std::ostringstream text;
    text << in.rdbuf();
    Result<Hlog> log = parse_hlog(text.str());
    if (!log.ok()) return std::move(log).error().prefixed(path);
    return log;
}

}  // namespace mbstorm::report
