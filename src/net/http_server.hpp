// A tiny HTTP/1.1 server on its own thread, for `--metrics-listen`: it answers GET (and HEAD)
// with what a handler returns for the path, each connection closed after its answer. Nothing
// here touches an engine's ring, so the hot path pays nothing for it. Every connection is
// served at once (poll, no thread per client), each with a deadline for its whole request and
// one for its answer, at most 64 at a time (a new one closes the oldest): a dripping, silent
// or never-reading client holds up neither a scrape nor stop(). Bad requests get 400, other
// methods 405, oversized heads 431.
#pragma once

#include <functional>
#include <string>
#include <string_view>
#include <thread>

#include "net/socket.hpp"

namespace mbstorm::net {

struct HttpReply {
    int status = 200;
    std::string content_type = "text/plain; charset=utf-8";
    std::string body;
};

class HttpServer {
  public:
    // Called on the server's thread with the request's path (without its query string).
    using Handler = std::function<HttpReply(std::string_view path)>;

    HttpServer() = default;
    HttpServer(const HttpServer&) = delete;
    HttpServer& operator=(const HttpServer&) = delete;
    ~HttpServer() { stop(); }

    // listen: HOST:PORT (port 0: any free port). An error when it cannot listen: InvalidInput
    // for bad text, Network (the system's reason alone) when the listen fails.
    Error start(std::string_view listen, Handler handler);
    // Closes every client connection and the listener; returns at once, whatever the clients
    // are doing.
    void stop() noexcept;
    bool running() const noexcept { return thread_.joinable(); }
    // The address it listens on, e.g. "127.0.0.1:40123" or "[::1]:9100".
    const std::string& address() const noexcept { return address_; }

  private:
    void serve() noexcept;

    Handler handler_;
    UniqueFd listener_;
    UniqueFd wake_;  // eventfd: stop() writes it to end serve()
    std::thread thread_;
    std::string address_;
};

// The response bytes for a reply (status line, Content-Type, Content-Length, Connection:
// close); head: without the body.
std::string http_response(const HttpReply& reply, bool head);

// The most a request head may take: a longer one without its blank line is answered 431.
inline constexpr std::size_t kMaxRequestHead = 8192;

// What the server answers a client that has sent `received` so far (everything it read, its
// head's end not seen before): "" while the head is incomplete and within kMaxRequestHead,
// else the whole response: 431 for a head past the cap, 400 for a malformed request line, 405
// for another method than GET or HEAD, else the handler's reply for the path. `too_large` says
// which answers are 431s (the server then drains the connection). Pure, so that the fuzz
// harness (fuzz/http_head.cpp) can feed it exactly what the socket loop does.
std::string answer_received(std::string_view received,
                            const std::function<HttpReply(std::string_view path)>& handler,
                            bool& too_large);

// Parses a request head ("GET /metrics?x HTTP/1.1\r\n..."): method and path (no query), or
// false when the request line is malformed.
bool parse_http_request_line(std::string_view head, std::string& method, std::string& path);

}  // namespace mbstorm::net
