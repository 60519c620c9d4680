#include "cli/distributed_options.hpp"

#include <fmt/format.h>

#include <charconv>
#include <cmath>
#include <cstdint>

#include "load/shard.hpp"

namespace mbstorm::cli {
namespace {

using Clock = std::chrono::system_clock;

// A whole number of at most 9 digits (shard numbers, date fields): false otherwise.
bool parse_count(std::string_view text, std::uint32_t& out) {
    if (text.empty() || text.size() > 9) return false;
    for (char c : text)
        if (c < '0' || c > '9') return false;
    std::from_chars(text.data(), text.data() + text.size(), out);
    return true;
}

std::string check_shard(std::uint32_t index, std::uint32_t count) {
    if (count < 1 || count > load::kMaxShards)
        return fmt::format("shard count {} is out of range (valid 1..{})", count, load::kMaxShards);
    if (index >= count)
        return fmt::format(
            "index {} is out of range for {} shard{} (valid 0..{}: shards count from 0)", index,
            count, count == 1 ? "" : "s", count - 1);
    return {};
}

// Seconds since the epoch, possibly fractional ("1795528800.25"); false when not that form.
bool parse_epoch(std::string_view text, Clock::time_point& out) {
    const auto dot = text.find('.');
    const std::string_view whole = text.substr(0, dot);
    if (whole.empty() || whole.size() > 12) return false;
    for (char c : whole)
        if (c < '0' || c > '9') return false;
    std::int64_t seconds = 0;
    std::from_chars(whole.data(), whole.data() + whole.size(), seconds);
    std::int64_t nanos = 0;
    if (dot != std::string_view::npos) {
        const std::string_view frac = text.substr(dot + 1);
        if (frac.empty() || frac.size() > 9) return false;
        for (char c : frac)
            if (c < '0' || c > '9') return false;
        std::uint32_t value = 0;
        parse_count(frac, value);
        nanos = value;
        for (std::size_t i = frac.size(); i < 9; ++i) nanos *= 10;
    }
    out = Clock::time_point(std::chrono::duration_cast<Clock::duration>(
        std::chrono::seconds(seconds) + std::chrono::nanoseconds(nanos)));
    return true;
}

// RFC 3339 date-time: YYYY-MM-DDTHH:MM:SS[.frac](Z|+HH:MM|-HH:MM); "" or what is wrong.
std::string parse_rfc3339(std::string_view text, Clock::time_point& out) {
    auto field = [&](std::size_t at, std::size_t len, std::uint32_t& v) {
        return at + len <= text.size() && parse_count(text.substr(at, len), v);
    };
    std::uint32_t y = 0, mo = 0, d = 0, h = 0, mi = 0, s = 0;
    if (!field(0, 4, y) || text.size() < 19 || text[4] != '-' || !field(5, 2, mo) ||
        text[7] != '-' || !field(8, 2, d) || (text[10] != 'T' && text[10] != 't') ||
        !field(11, 2, h) || text[13] != ':' || !field(14, 2, mi) || text[16] != ':' ||
        !field(17, 2, s))
        return "not of the form 2026-11-24T14:00:00Z";
    const std::chrono::year_month_day date{std::chrono::year(static_cast<int>(y)),
                                           std::chrono::month(mo), std::chrono::day(d)};
    if (!date.ok() || h > 23 || mi > 59 || s > 60) return "no such date or time of day";
    std::size_t at = 19;
    std::int64_t nanos = 0;
    if (at < text.size() && text[at] == '.') {
        std::size_t end = at + 1;
        while (end < text.size() && text[end] >= '0' && text[end] <= '9') ++end;
        if (end == at + 1) return "a '.' with no fraction of a second after it";
        std::string_view frac = text.substr(at + 1, std::min<std::size_t>(end - at - 1, 9));
        std::uint32_t value = 0;
        parse_count(frac, value);
        nanos = value;
        for (std::size_t i = frac.size(); i < 9; ++i) nanos *= 10;
        at = end;
    }
    std::int64_t offset_minutes = 0;
    if (at < text.size() && (text[at] == 'Z' || text[at] == 'z') && at + 1 == text.size()) {
        // UTC
    } else if (at < text.size() && (text[at] == '+' || text[at] == '-')) {
        std::uint32_t oh = 0, om = 0;
        if (text.size() != at + 6 || !field(at + 1, 2, oh) || text[at + 3] != ':' ||
            !field(at + 4, 2, om) || oh > 23 || om > 59)
            return "a UTC offset must be +HH:MM or -HH:MM";
        offset_minutes = (text[at] == '+' ? 1 : -1) * static_cast<std::int64_t>(oh * 60 + om);
    } else {
        return "no time zone: end it with Z (UTC) or an offset like +01:00";
    }
    // A leap second (:60) lands on the next second, as the epoch counts them.
    const auto t = std::chrono::sys_days(date).time_since_epoch() + std::chrono::hours(h) +
                   std::chrono::minutes(mi) + std::chrono::seconds(s) +
                   std::chrono::nanoseconds(nanos) - std::chrono::minutes(offset_minutes);
    out = Clock::time_point(std::chrono::duration_cast<Clock::duration>(t));
    return {};
}

}  // namespace

namespace {

// resolve_shard's work: "" or what is wrong.
std::string shard_problem(const std::string& flag, const char* env_index, const char* env_count,
                          load::Plan::Shard& out) {
    out = {};
    std::uint32_t index = 0, count = 0;
    if (!flag.empty()) {
        const auto slash = flag.find('/');
        if (slash == std::string::npos ||
            !parse_count(std::string_view(flag).substr(0, slash), index) ||
            !parse_count(std::string_view(flag).substr(slash + 1), count))
            return fmt::format("--shard '{}': expected I/N, e.g. 0/3 (shard I of N, from 0)", flag);
        if (auto e = check_shard(index, count); !e.empty())
            return fmt::format("--shard '{}': {}", flag, e);
    } else {
        if (env_count == nullptr || *env_count == '\0') return {};  // not sharded
        if (!parse_count(env_count, count))
            return fmt::format("{}='{}': expected the shard count, a whole number", kShardCountEnv,
                               env_count);
        if (env_index == nullptr || *env_index == '\0')
            return fmt::format(
                "{}={} is set but {} is not (run as a Kubernetes Indexed Job, or give --shard I/N)",
                kShardCountEnv, env_count, kShardIndexEnv);
        if (!parse_count(env_index, index))
            return fmt::format("{}='{}': expected the shard index, a whole number", kShardIndexEnv,
                               env_index);
        if (auto e = check_shard(index, count); !e.empty())
            return fmt::format("{}={}, {}={}: {}", kShardIndexEnv, env_index, kShardCountEnv,
                               env_count, e);
    }
    out = {index, count};
    return {};
}

// parse_start_at's work: "" or what is wrong.
std::string start_at_problem(std::string_view text, Clock::time_point now, Clock::time_point& out) {
    const bool epoch_form = !text.empty() && text.find('-') == std::string_view::npos &&
                            text.find(':') == std::string_view::npos;
    if (epoch_form) {
        if (!parse_epoch(text, out))
            return fmt::format(
                "--start-at '{}': not seconds since the epoch (e.g. 1795528800 or 1795528800.5) "
                "nor RFC 3339 (e.g. 2026-11-24T14:00:00Z)",
                text);
    } else if (auto e = parse_rfc3339(text, out); !e.empty()) {
        return fmt::format(
            "--start-at '{}': {} (RFC 3339, e.g. 2026-11-24T14:00:00Z or "
            "2026-11-24T15:00:00+01:00, or seconds since the epoch)",
            text, e);
    }
    const auto distance = out > now ? out - now : now - out;
    if (distance > kMaxStartAtDistance) {
        const double hours = std::chrono::duration<double, std::ratio<3600>>(distance).count();
        return fmt::format(
            "--start-at '{}' is {:.1f} h {} (at most {} h either way: check the time and this "
            "machine's clock)",
            text, hours, out > now ? "ahead" : "ago", kMaxStartAtDistance.count());
    }
    return {};
}

}  // namespace

Error resolve_shard(const std::string& flag, const char* env_index, const char* env_count,
                    load::Plan::Shard& out) {
    std::string why = shard_problem(flag, env_index, env_count, out);
    if (why.empty()) return {};
    return Error(ErrorCode::InvalidInput, std::move(why));
}

Error parse_start_at(std::string_view text, Clock::time_point now, Clock::time_point& out) {
    std::string why = start_at_problem(text, now, out);
    if (why.empty()) return {};
    return Error(ErrorCode::InvalidInput, std::move(why));
}

}  // namespace mbstorm::cli
