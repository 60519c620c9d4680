// `--metrics-listen`: the HTTP endpoint of run's and serve's live metrics, and serve's
// exposition (run's is report::format_load_metrics).
#pragma once

#include <functional>
#include <string>
#include <string_view>

#include "net/http_server.hpp"
#include "server/stats.hpp"

namespace mbstorm::cli {

// Serves GET /metrics with exposition() (404 elsewhere) and says where on stderr
// ("metrics on http://127.0.0.1:40123/metrics"). False, with the reason on stderr, when it
// cannot listen. command: "run" or "serve", for messages.
bool start_metrics_endpoint(net::HttpServer& http, const std::string& listen,
                            std::string_view command, std::function<std::string()> exposition);

// `mbstorm serve`'s metrics (names: docs/metrics.md).
std::string format_serve_metrics(const server::ServerStats& stats);

}  // namespace mbstorm::cli
