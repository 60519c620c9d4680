#include "cli/metrics_endpoint.hpp"

#include <fmt/format.h>

#include <cstdio>

#include "codec/exception_code.hpp"
#include "codec/function_code.hpp"
#include "report/prometheus.hpp"

namespace mbstorm::cli {

bool start_metrics_endpoint(net::HttpServer& http, const std::string& listen,
                            std::string_view command, std::function<std::string()> exposition) {
    auto handler = [exposition = std::move(exposition)](std::string_view path) {
        if (path != "/metrics")
            return net::HttpReply{404, "text/plain; charset=utf-8", "metrics are at /metrics\n"};
        return net::HttpReply{200, std::string(report::kPrometheusContentType), exposition()};
    };
    if (const Error error = http.start(listen, std::move(handler)); !error.ok()) {
        fmt::print(stderr, "mbstorm {}: cannot serve --metrics-listen {}: {}\n", command, listen,
                   error.text());
        return false;
    }
    fmt::print(stderr, "mbstorm {}: metrics on http://{}/metrics\n", command, http.address());
    std::fflush(stderr);
    return true;
}

std::string format_serve_metrics(const server::ServerStats& s) {
    using report::PromLabel;
    report::PrometheusWriter w;
    const std::span<const PromLabel> none;
    auto counter = [&](std::string_view name, std::string_view help, std::uint64_t value) {
        w.family(name, "counter", help);
        w.sample(name, none, value);
    };
    auto gauge = [&](std::string_view name, std::string_view help, std::uint64_t value) {
        w.family(name, "gauge", help);
        w.sample(name, none, value);
    };
    w.family("mbstorm_slave_requests_total", "counter",
             "Well-framed requests received, by function code.");
    for (std::size_t fc = 0; fc < s.requests_by_function.size(); ++fc) {
        if (s.requests_by_function[fc] == 0) continue;
        const std::string_view known = codec::function_name(static_cast<std::uint8_t>(fc));
        const std::string name = known.empty() ? fmt::format("0x{:02x}", fc) : std::string(known);
        const PromLabel labels[] = {{"function", name}};
        w.sample("mbstorm_slave_requests_total", labels, s.requests_by_function[fc]);
    }
    counter("mbstorm_slave_transactions_total",
            "Requests answered (with a normal or an exception response).", s.transactions);
    w.family("mbstorm_slave_exceptions_total", "counter",
             "Exception responses sent, by exception code.");
    for (std::size_t code = 1; code < s.exceptions.size(); ++code) {
        if (s.exceptions[code] == 0) continue;
        const std::string text = fmt::format("0x{:02x}", code);
        const PromLabel labels[] = {{"exception", text}};
        w.sample("mbstorm_slave_exceptions_total", labels, s.exceptions[code]);
    }
    counter("mbstorm_slave_received_bytes_total", "Bytes received from clients.", s.bytes_in);
    counter("mbstorm_slave_sent_bytes_total", "Bytes sent to clients.", s.bytes_out);
    counter("mbstorm_slave_connections_accepted_total", "Connections accepted.",
            s.connections_total);
    gauge("mbstorm_slave_open_connections", "Connections open now.", s.connections_current);
    w.family("mbstorm_slave_connections_closed_total", "counter",
             "Connections the slave closed or turned away, by reason.");
    const std::pair<const char*, std::uint64_t> closes[] = {{"idle", s.idle_closes},
                                                            {"slow_frame", s.frame_timeouts},
                                                            {"bad_framing", s.bad_framing_closes},
                                                            {"bad_crc", s.crc_errors},
                                                            {"evicted", s.evictions},
                                                            {"refused", s.refusals},
                                                            {"fault_drop", s.fault_drops}};
    for (const auto& [why, n] : closes) {
        const PromLabel labels[] = {{"reason", why}};
        w.sample("mbstorm_slave_connections_closed_total", labels, n);
    }
    w.family("mbstorm_slave_malformed_input_total", "counter",
             "Input that was not a usable Modbus TCP request, by kind.");
    const std::pair<const char*, std::uint64_t> malformed[] = {
        {"bad_length", s.bad_framing_closes},
        {"bad_crc", s.crc_errors},
        {"protocol_id", s.discarded_frames},
        {"incomplete_frame", s.frame_timeouts}};
    for (const auto& [kind, n] : malformed) {
        const PromLabel labels[] = {{"kind", kind}};
        w.sample("mbstorm_slave_malformed_input_total", labels, n);
    }
    counter("mbstorm_slave_busy_rejects_total",
            "Requests answered with exception 06 by the outstanding-request cap.", s.busy_rejects);
    counter("mbstorm_slave_foreign_unit_requests_total", "Requests for another unit id.",
            s.foreign_unit);
    counter("mbstorm_slave_accept_out_of_descriptors_total",
            "Accepts that failed for lack of file descriptors.", s.accept_fd_exhausted);
    gauge("mbstorm_slave_pending_output_bytes", "Bytes queued for sending now.", s.pending_output);
    // Modbus/TCP Security (--transport tls); zero on other transports.
    report::write_tls_counters(
        w, "mbstorm_slave_", none,
        {s.tls_handshakes, s.tls_resumed, s.tls_refused, s.tls_offloaded, s.tls_offload_errors});
    counter("mbstorm_slave_tls_role_refusals_total",
            "Requests answered with exception 01 because the client's role may not use the "
            "function.",
            s.tls_role_denied);
    return w.text();
}

}  // namespace mbstorm::cli
