#include "net/http_server.hpp"

#include <poll.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace mbstorm::net {
namespace {

constexpr std::size_t kMaxRequestHead = 8192;
constexpr int kIoTimeoutMs = 2000;  // a peer slower than this is dropped

const char* reason(int status) {
    switch (status) {
        case 200:
            return "OK";
        case 400:
            return "Bad Request";
        case 404:
            return "Not Found";
        case 405:
            return "Method Not Allowed";
        case 431:
            return "Request Header Fields Too Large";
        default:
            return "Internal Server Error";
    }
}

void set_io_timeouts(int fd) {
    timeval tv{kIoTimeoutMs / 1000, (kIoTimeoutMs % 1000) * 1000};
    ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
    ::setsockopt(fd, SOL_SOCKET, SO_SNDTIMEO, &tv, sizeof tv);
}

// After an answer to a request not read whole (431): no more to send, and what the client
// still sends is read and dropped for a moment, so that closing does not reset the connection
// and throw away the answer with it. Bounded in bytes and time: the server is one thread.
void close_gracefully(int fd) {
    ::shutdown(fd, SHUT_WR);
    const timeval tv{0, 100'000};
    ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
    char sink[4096];
    for (std::size_t drained = 0; drained < 16 * kMaxRequestHead;) {
        const ssize_t n = ::recv(fd, sink, sizeof sink, 0);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) return;
        drained += static_cast<std::size_t>(n);
    }
}

void send_all(int fd, std::string_view bytes) {
    while (!bytes.empty()) {
        const ssize_t n = ::send(fd, bytes.data(), bytes.size(), MSG_NOSIGNAL);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) return;  // gone or too slow: nothing more to do for it
        bytes.remove_prefix(static_cast<std::size_t>(n));
    }
}

}  // namespace

std::string http_response(const HttpReply& reply, bool head) {
    std::string out = "HTTP/1.1 " + std::to_string(reply.status) + " " + reason(reply.status) +
                      "\r\nContent-Type: " + reply.content_type +
                      "\r\nContent-Length: " + std::to_string(reply.body.size()) +
                      "\r\nConnection: close\r\n\r\n";
    if (!head) out += reply.body;
    return out;
}

bool parse_http_request_line(std::string_view head, std::string& method, std::string& path) {
    const std::size_t eol = head.find("\r\n");
    const std::string_view line = head.substr(0, eol);
    const std::size_t sp1 = line.find(' ');
    if (sp1 == std::string_view::npos || sp1 == 0) return false;
    const std::size_t sp2 = line.find(' ', sp1 + 1);
    if (sp2 == std::string_view::npos || sp2 == sp1 + 1) return false;
    const std::string_view version = line.substr(sp2 + 1);
    if (version.rfind("HTTP/1.", 0) != 0) return false;
    std::string_view target = line.substr(sp1 + 1, sp2 - sp1 - 1);
    if (target.front() != '/') return false;
    target = target.substr(0, target.find('?'));
    method.assign(line.substr(0, sp1));
    path.assign(target);
    return true;
}

bool HttpServer::start(std::string_view listen, Handler handler, std::string& error) {
    Endpoint endpoint;
    if (!parse_endpoint(listen, endpoint, &error, 0)) return false;
    ListenOptions options;
    options.backlog = 16;
    options.reuse_port = false;
    options.nonblocking = false;
    const int fd = listen_socket(endpoint, options);
    if (fd < 0) {
        error = std::strerror(-fd);
        return false;
    }
    listener_.reset(fd);
    endpoint.set_port(local_port(fd));
    address_ = endpoint.to_string();
    const int wake = ::eventfd(0, EFD_CLOEXEC);
    if (wake < 0) {
        error = std::strerror(errno);
        listener_.reset();
        return false;
    }
    wake_.reset(wake);
    handler_ = std::move(handler);
    thread_ = std::thread([this] { serve(); });
    return true;
}

void HttpServer::stop() noexcept {
    if (!thread_.joinable()) return;
    const std::uint64_t one = 1;
    [[maybe_unused]] const ssize_t n = ::write(wake_.get(), &one, sizeof one);
    thread_.join();
    listener_.reset();
    wake_.reset();
}

void HttpServer::serve() noexcept {
    for (;;) {
        pollfd fds[2] = {{listener_.get(), POLLIN, 0}, {wake_.get(), POLLIN, 0}};
        const int rc = ::poll(fds, 2, -1);
        if (rc < 0 && errno == EINTR) continue;
        if (rc < 0 || (fds[1].revents & POLLIN) != 0) return;
        if ((fds[0].revents & POLLIN) == 0) continue;
        UniqueFd client(::accept4(listener_.get(), nullptr, nullptr, SOCK_CLOEXEC));
        if (!client.valid()) continue;  // e.g. the peer gave up already, or out of descriptors
        answer(client.get());
    }
}

void HttpServer::answer(int fd) noexcept {
    set_io_timeouts(fd);
    std::string head;
    char buffer[2048];
    while (head.find("\r\n\r\n") == std::string::npos) {
        if (head.size() > kMaxRequestHead) {
            send_all(fd, http_response({431, "text/plain; charset=utf-8", "request too large\n"},
                                       false));
            close_gracefully(fd);
            return;
        }
        const ssize_t n = ::recv(fd, buffer, sizeof buffer, 0);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) return;  // closed, or too slow
        head.append(buffer, static_cast<std::size_t>(n));
    }
    std::string method, path;
    HttpReply reply;
    if (!parse_http_request_line(head, method, path)) {
        reply = {400, "text/plain; charset=utf-8", "malformed request line\n"};
    } else if (method != "GET" && method != "HEAD") {
        reply = {405, "text/plain; charset=utf-8", "only GET and HEAD\n"};
    } else {
        try {
            reply = handler_(path);
        } catch (const std::exception& e) {
            reply = {500, "text/plain; charset=utf-8", std::string(e.what()) + "\n"};
        }
    }
    send_all(fd, http_response(reply, method == "HEAD"));
}

}  // namespace mbstorm::net
