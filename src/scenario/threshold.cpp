#include "scenario/threshold.hpp"

#include <fmt/format.h>

#include <cctype>
#include <charconv>
#include <cmath>

#include "stats/duration_text.hpp"

namespace mbstorm::scenario {
namespace {

std::string_view trim(std::string_view s) {
    while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
    while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
    return s;
}

bool parse_double(std::string_view s, double& out) {
    if (s.empty()) return false;
    const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), out);
    return ec == std::errc() && ptr == s.data() + s.size() && std::isfinite(out);
}

constexpr const char* kMetricHelp =
    "metrics: p50, p90, p99, p99.9 (any pN with 0 < N <= 100), min, max, mean, error_rate, "
    "errors, throughput, transactions, exceptions, exceptions[XX] (hex code), timeouts, "
    "mismatches";

bool parse_metric(std::string_view m, ThresholdSpec& out, std::string& error) {
    if (m == "min")
        out.metric = Metric::Min;
    else if (m == "max")
        out.metric = Metric::Max;
    else if (m == "mean")
        out.metric = Metric::Mean;
    else if (m == "error_rate")
        out.metric = Metric::ErrorRate;
    else if (m == "errors")
        out.metric = Metric::Errors;
    else if (m == "throughput")
        out.metric = Metric::Throughput;
    else if (m == "transactions")
        out.metric = Metric::Transactions;
    else if (m == "timeouts")
        out.metric = Metric::Timeouts;
    else if (m == "mismatches")
        out.metric = Metric::Mismatches;
    else if (m == "exceptions") {
        out.metric = Metric::Exceptions;
        out.exception_code = -1;
    } else if (m.starts_with("exceptions[") && m.ends_with("]")) {
        std::string_view code = m.substr(11, m.size() - 12);
        if (code.starts_with("0x") || code.starts_with("0X")) code.remove_prefix(2);
        unsigned value = 0;
        const auto [ptr, ec] = std::from_chars(code.data(), code.data() + code.size(), value, 16);
        if (code.empty() || ec != std::errc() || ptr != code.data() + code.size() || value > 0xFF) {
            error =
                fmt::format("'{}': the exception code must be hex 01..FF, e.g. exceptions[02]", m);
            return false;
        }
        out.metric = Metric::Exceptions;
        out.exception_code = static_cast<int>(value);
    } else if (m.size() > 1 && m.front() == 'p') {
        double p = 0;
        if (!parse_double(m.substr(1), p)) {
            error = fmt::format("unknown metric '{}' ({})", m, kMetricHelp);
            return false;
        }
        if (!(p > 0 && p <= 100)) {
            error = fmt::format("percentile '{}' is out of range (valid p0 < pN <= p100)", m);
            return false;
        }
        out.metric = Metric::Percentile;
        out.percentile = p;
    } else {
        error = fmt::format("unknown metric '{}' ({})", m, kMetricHelp);
        return false;
    }
    return true;
}

bool is_latency(Metric m) {
    return m == Metric::Percentile || m == Metric::Min || m == Metric::Max || m == Metric::Mean;
}

bool parse_limit(std::string_view v, ThresholdSpec& out, std::string& error) {
    if (is_latency(out.metric)) {
        std::uint64_t ns = 0;
        const bool has_unit = !v.empty() && std::isalpha(static_cast<unsigned char>(v.back()));
        if (!has_unit || !stats::parse_duration_ns(v, ns)) {
            error = fmt::format(
                "'{}' is not a latency: give a number with a unit (ns, us, ms, s), "
                "e.g. 5ms",
                v);
            return false;
        }
        out.limit = static_cast<double>(ns);
        return true;
    }
    if (out.metric == Metric::ErrorRate) {
        double r = 0;
        const bool percent = v.ends_with("%");
        if (!parse_double(trim(percent ? v.substr(0, v.size() - 1) : v), r)) {
            error = fmt::format(
                "'{}' is not a rate: give a percentage (0.1%) or a fraction (0.001)", v);
            return false;
        }
        if (percent) r /= 100.0;
        if (r < 0 || r > 1) {
            error = fmt::format("error_rate limit '{}' is out of range (valid 0%..100%)", v);
            return false;
        }
        out.limit = r;
        return true;
    }
    if (out.metric == Metric::Throughput) {
        std::string_view n = v;
        if (n.ends_with("/s")) n = trim(n.substr(0, n.size() - 2));
        double scale = 1;
        if (n.ends_with("k")) scale = 1e3;
        if (n.ends_with("M")) scale = 1e6;
        if (scale != 1) n.remove_suffix(1);
        double r = 0;
        if (!parse_double(n, r) || r < 0) {
            error = fmt::format(
                "'{}' is not a throughput: give transactions per second, e.g. "
                "50000/s or 50k/s",
                v);
            return false;
        }
        out.limit = r * scale;
        return true;
    }
    std::uint64_t count = 0;
    const auto [ptr, ec] = std::from_chars(v.data(), v.data() + v.size(), count);
    if (v.empty() || ec != std::errc() || ptr != v.data() + v.size()) {
        error = fmt::format("'{}' is not a count: give a whole number >= 0", v);
        return false;
    }
    out.limit = static_cast<double>(count);
    return true;
}

const char* comparison_text(Comparison c) {
    switch (c) {
        case Comparison::Less:
            return "<";
        case Comparison::LessEqual:
            return "<=";
        case Comparison::Greater:
            return ">";
        case Comparison::GreaterEqual:
            return ">=";
        case Comparison::Equal:
            return "==";
        case Comparison::NotEqual:
            return "!=";
    }
    return "?";
}

bool compare(double observed, Comparison c, double limit) {
    switch (c) {
        case Comparison::Less:
            return observed < limit;
        case Comparison::LessEqual:
            return observed <= limit;
        case Comparison::Greater:
            return observed > limit;
        case Comparison::GreaterEqual:
            return observed >= limit;
        case Comparison::Equal:
            return observed == limit;
        case Comparison::NotEqual:
            return observed != limit;
    }
    return false;
}

bool parse_expression(std::string_view text, ThresholdSpec& out, std::string& error) {
    const std::string_view t = trim(text);
    const std::size_t op_pos = t.find_first_of("<>=!");
    if (op_pos == std::string_view::npos) {
        error = fmt::format(
            "'{}' has no comparison: write METRIC OP VALUE with OP one of <, <=, "
            ">, >=, ==, != (e.g. p99 < 5ms)",
            t);
        return false;
    }
    const std::string_view metric = trim(t.substr(0, op_pos));
    std::string_view rest = t.substr(op_pos);
    static constexpr std::pair<std::string_view, Comparison> kOps[] = {
        {"<=", Comparison::LessEqual}, {">=", Comparison::GreaterEqual},
        {"==", Comparison::Equal},     {"!=", Comparison::NotEqual},
        {"<", Comparison::Less},       {">", Comparison::Greater}};
    bool found = false;
    for (const auto& [sym, cmp] : kOps) {
        if (rest.starts_with(sym)) {
            out.comparison = cmp;
            rest.remove_prefix(sym.size());
            found = true;
            break;
        }
    }
    if (!found) {
        error = fmt::format("'{}': unknown comparison (valid <, <=, >, >=, ==, !=)", t);
        return false;
    }
    const std::string_view value = trim(rest);
    if (metric.empty()) {
        error = fmt::format("'{}' has no metric before the comparison ({})", t, kMetricHelp);
        return false;
    }
    if (value.empty()) {
        error = fmt::format("'{}' has no value after the comparison", t);
        return false;
    }
    if (!parse_metric(metric, out, error) || !parse_limit(value, out, error)) return false;
    out.text = fmt::format("{} {} {}", metric, comparison_text(out.comparison), value);
    return true;
}

}  // namespace

Result<ThresholdSpec> parse_threshold(std::string_view text) {
    ThresholdSpec spec;
    if (std::string error; !parse_expression(text, spec, error))
        return Error(ErrorCode::InvalidInput, std::move(error));
    return spec;
}

std::string format_metric_value(Metric metric, double value) {
    if (is_latency(metric)) {
        if (value < 1e3) return fmt::format("{:.0f}ns", value);
        if (value < 1e6) return fmt::format("{:.3g}µs", value / 1e3);  // as every report prints it
        if (value < 1e9) return fmt::format("{:.3g}ms", value / 1e6);
        return fmt::format("{:.3g}s", value / 1e9);
    }
    if (metric == Metric::ErrorRate) return fmt::format("{:.4g}%", value * 100.0);
    if (metric == Metric::Throughput) return fmt::format("{:.0f}/s", value);
    return fmt::format("{:.0f}", value);
}

stats::ThresholdResult evaluate_threshold(const ThresholdSpec& spec, const stats::RunResult& run) {
    stats::ThresholdResult result;
    result.expression = spec.operation.empty() ? spec.text : spec.operation + ": " + spec.text;
    const stats::Histogram* latency = &run.latency;
    const stats::OutcomeCounters* counters = &run.counters;
    if (!spec.operation.empty()) {
        latency = nullptr;
        for (const auto& op : run.operations) {
            if (op.name == spec.operation) {
                latency = &op.latency;
                counters = &op.counters;
                break;
            }
        }
        if (latency == nullptr) {
            result.observed_text = "no such operation in the results";
            return result;
        }
    }
    const std::uint64_t completed = counters->completed();
    double observed = 0;
    switch (spec.metric) {
        case Metric::Percentile:
        case Metric::Min:
        case Metric::Max:
        case Metric::Mean:
            // A latency limit over no samples would pass vacuously: fail it instead.
            if (latency->empty()) {
                result.observed_text = "no samples";
                return result;
            }
            observed = spec.metric == Metric::Percentile
                           ? static_cast<double>(latency->value_at_percentile(spec.percentile))
                       : spec.metric == Metric::Min ? static_cast<double>(latency->min())
                       : spec.metric == Metric::Max ? static_cast<double>(latency->max())
                                                    : latency->mean();
            break;
        case Metric::ErrorRate:
            if (completed == 0) {
                result.observed_text = "no transactions";
                return result;
            }
            observed = static_cast<double>(counters->errors()) / static_cast<double>(completed);
            break;
        case Metric::Errors:
            // Stray responses answer no transaction, but a target that sends them is faulty.
            observed = static_cast<double>(counters->errors() + counters->stray_responses());
            break;
        case Metric::Throughput:
            observed = run.metadata.measured_duration_ns == 0
                           ? 0.0
                           : static_cast<double>(completed) * 1e9 /
                                 static_cast<double>(run.metadata.measured_duration_ns);
            break;
        case Metric::Transactions:
            observed = static_cast<double>(completed);
            break;
        case Metric::Exceptions:
            observed = static_cast<double>(
                spec.exception_code < 0
                    ? counters->count(stats::Outcome::Exception)
                    : counters->exceptions[static_cast<std::size_t>(spec.exception_code)]);
            break;
        case Metric::Timeouts:
            observed = static_cast<double>(counters->count(stats::Outcome::Timeout));
            break;
        case Metric::Mismatches:
            observed = static_cast<double>(counters->count(stats::Outcome::ValueMismatch));
            break;
    }
    result.observed = observed;
    result.observed_text = format_metric_value(spec.metric, observed);
    result.passed = compare(observed, spec.comparison, spec.limit);
    return result;
}

}  // namespace mbstorm::scenario
