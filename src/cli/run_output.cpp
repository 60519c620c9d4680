#include "cli/run_output.hpp"

#include "cli/duration_option.hpp"

#include <fmt/format.h>

#include "cli/commands.hpp"
#include "report/files.hpp"
#include "report/hgrm.hpp"
#include "report/html.hpp"
#include "report/json.hpp"
#include "report/junit.hpp"

namespace mbstorm::cli {

void add_output_options(CLI::App* cmd, OutputFiles& files) {
    cmd->add_option("--json", files.json,
                    "write a machine-readable summary (schema: docs/json-schema.md; '-': stdout)");
    cmd->add_option("--hdr", files.hdr,
                    "write the latency distribution in HdrHistogram's .hgrm format ('-': stdout)");
    cmd->add_option("--html", files.html,
                    "write a self-contained HTML report with plots ('-': stdout)");
}

void add_run_identity_options(CLI::App* cmd, OutputFiles& files) {
    cmd->add_option("--hlog", files.hlog,
                    "write the latency as an HdrHistogram interval log, one line per interval and "
                    "operation, as the run goes (for mbstorm merge and HdrHistogram's tools)");
    cmd->add_option("--timeline", files.timeline,
                    "write the timeline as JSON Lines, one object per interval (keys: "
                    "docs/json-schema.md), each flushed as soon as the interval is complete");
    cmd->add_option("--test-id", files.test_id,
                    "name of the test this run belongs to, kept in --json and --hlog: mbstorm "
                    "merge refuses runs of different tests");
    cmd->add_option("--metrics-listen", files.metrics_listen,
                    "serve live metrics at http://HOST:PORT/metrics (Prometheus text format) "
                    "while the run goes; port 0: any free port, printed on stderr");
    add_duration_option(cmd, "--metrics-linger", files.metrics_linger_ns,
                        "after the run, keep --metrics-listen up with the final values (the "
                        "running gauge at 0) until one scrape has taken them, for at most this "
                        "long (e.g. a scrape interval and a bit); Ctrl-C ends it early")
        ->needs(cmd->get_option("--metrics-listen"));
}

Error stdout_conflict(const OutputFiles& files) {
    int n = 0;
    for (const std::string* f : {&files.json, &files.hdr, &files.html, &files.junit})
        n += *f == "-" ? 1 : 0;
    if (n <= 1) return {};
    return Error(ErrorCode::InvalidInput,
                 "only one of --json, --hdr, --html and --junit can be '-' (stdout)");
}

void LiveProgress::update(const load::ProgressSnapshot& s) {
    if (quiet_) return;
    last_.index = s.interval_index;
    last_.transactions = static_cast<std::uint64_t>(s.transactions_per_second);
    last_.duration_ns = 1'000'000'000ULL;
    last_.errors = s.errors;
    last_.p50_ns = s.p50_ns;
    last_.p99_ns = s.p99_ns;
    last_.max_ns = s.max_ns;
    report::ProgressSample sample;
    sample.elapsed_seconds = s.elapsed_seconds;
    sample.last_interval = &last_;
    sample.total_transactions = s.total_transactions;
    sample.total_errors = s.errors;
    sample.open_connections = s.open_connections;
    printer_.update(sample);
}

int report_run(load::LoadResult& result, const OutputFiles& files) {
    int code = kExitOk;
    // The content is made only for a file asked for: a merged soak's JSON document alone is
    // some 2 KB per timeline interval.
    auto write = [&code](const std::string& path, const auto& make_content, const char* what) {
        if (path.empty()) return;
        if (Error bad = report::write_text_file(path, make_content()); !bad.ok()) {
            fmt::print(stderr, "mbstorm run: cannot write {} {}: {}\n", what, path, bad.text());
            code = kExitUsage;
        } else {
            fmt::print(stderr, "wrote {} {}\n", what, path == "-" ? "to stdout" : path);
        }
    };
    auto write_junit = [&] {
        if (files.junit.empty()) return;
        write(
            files.junit,
            [&] {
                return report::format_junit(result.run, files.junit_suite, result.error.text());
            },
            "JUnit XML");
    };
    for (const auto& w : result.warnings) fmt::print(stderr, "mbstorm run: warning: {}\n", w);
    if (!result.ok() && result.run.counters.transactions_sent == 0) {
        fmt::print(stderr, "mbstorm run: {}\n", result.error.text());
        write_junit();
        return kExitUsage;
    }
    if (!result.ok())
        fmt::print(stderr, "mbstorm run: the run ended early: {}\n", result.error.text());
    // Everything measured is reported, even after an early end; on stderr when a report file
    // takes stdout.
    std::FILE* out = files.uses_stdout() ? stderr : stdout;
    fmt::print(out, "{}", report::format_console_report(result.run));
    if (result.pending_at_end)
        fmt::print(out, "  {} transaction(s) still pending when the run ended\n",
                   result.pending_at_end);
    std::fflush(out);
    write(
        files.json, [&] { return report::format_json(result.run); }, "JSON summary");
    write(
        files.hdr, [&] { return report::format_hgrm(result.run.latency); }, ".hgrm distribution");
    write(
        files.html, [&] { return report::format_html(result.run); }, "HTML report");
    write_junit();
    if (code == kExitOk) code = judge_run(result);
    return code;
}

int judge_run(const load::LoadResult& result) {
    const stats::OutcomeCounters& c = result.run.counters;
    if (c.transactions_sent > 0 && c.ok() == 0) {
        // Name the commonest failure, so the line alone says what went wrong.
        stats::Outcome worst = stats::Outcome::Timeout;
        for (std::size_t i = 1; i < stats::kOutcomeCount; ++i) {
            const auto o = static_cast<stats::Outcome>(i);
            if (!stats::is_stray(o) && c.count(o) > c.count(worst)) worst = o;
        }
        // None failed (all still pending when a short run ended): there is no commonest failure.
        const std::string most =
            c.errors() == 0 ? "" : fmt::format(", most as {}", stats::outcome_name(worst));
        fmt::print(stderr,
                   "mbstorm run: no transaction succeeded ({} sent, {} failed{}, {} pending at "
                   "the end)\n",
                   c.transactions_sent, c.errors(), most, result.pending_at_end);
        const stats::ConnectionStats& conns = result.run.connections;
        if (worst == stats::Outcome::ConnectionClosed && conns.tls_handshakes > 0)
            // TLS 1.3: the client's handshake ends before the server has checked its
            // certificate, and some servers (pymodbus) refuse it by closing, without an alert.
            fmt::print(stderr,
                       "mbstorm run: {} TLS handshakes completed and the target closed the "
                       "connections without an answer: it may refuse the client certificate or "
                       "its role (check --tls-cert, --tls-key and the CA the target trusts)\n",
                       conns.tls_handshakes);
        return kExitFailed;
    }
    if (result.target_lost_at_end) {
        for (const auto& note : result.run.metadata.notes)
            if (note.rfind("target lost", 0) == 0) fmt::print(stderr, "mbstorm run: {}\n", note);
        return kExitFailed;
    }
    return kExitOk;
}

}  // namespace mbstorm::cli
