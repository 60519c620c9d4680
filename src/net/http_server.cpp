#include "net/http_server.hpp"

#include <poll.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <memory>
#include <vector>

#include "net/clock.hpp"

namespace mbstorm::net {
namespace {

// A client has this long from its accept to send a whole request head, and as long again to
// take the answer: a slow or dripping one is closed then, whatever it keeps sending.
constexpr std::int64_t kExchangeDeadlineNs = 2 * kNsPerSec;
// After a 431, what the client still sends is read and dropped this long (and at most this
// much), so that closing does not reset the connection and throw the answer away with it.
constexpr std::int64_t kDrainNs = 100 * kNsPerMs;
constexpr std::size_t kMaxDrained = 16 * kMaxRequestHead;
// Connections served at once; a new one past this closes the oldest (the nearest its deadline
// anyway), so that a crowd of idle sockets cannot keep a scrape out.
constexpr std::size_t kMaxClients = 64;

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

// One connection: its request head as it comes, then its answer as it goes out.
struct Client {
    enum class Phase { Reading, Writing, Draining };
    UniqueFd fd;
    Phase phase = Phase::Reading;
    std::int64_t deadline_ns = 0;
    std::string in;
    std::string out;
    std::size_t sent = 0;
    bool drain_after = false;  // its head was not read whole (431)
    std::size_t drained = 0;
};

// The answer to a whole request head.
std::string reply_to(std::string_view head, const HttpServer::Handler& handler) {
    std::string method, path;
    HttpReply reply;
    if (!parse_http_request_line(head, method, path)) {
        reply = {400, "text/plain; charset=utf-8", "malformed request line\n"};
    } else if (method != "GET" && method != "HEAD") {
        reply = {405, "text/plain; charset=utf-8", "only GET and HEAD\n"};
    } else {
        try {
            reply = handler(path);
        } catch (const std::exception& e) {
            reply = {500, "text/plain; charset=utf-8", std::string(e.what()) + "\n"};
        }
    }
    return http_response(reply, method == "HEAD");
}

void start_answer(Client& c, std::string response, bool drain_after) {
    c.out = std::move(response);
    c.sent = 0;
    c.drain_after = drain_after;
    c.phase = Client::Phase::Writing;
    c.deadline_ns = now_ns() + kExchangeDeadlineNs;
}

// Reads what the client sent; false when it is to be closed.
bool read_request(Client& c, const HttpServer::Handler& handler) {
    char buffer[4096];
    for (;;) {
        const ssize_t n = ::recv(c.fd.get(), buffer, sizeof buffer, 0);
        if (n < 0 && errno == EINTR) continue;
        if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) return true;
        if (n <= 0) return false;  // closed, or reset
        c.in.append(buffer, static_cast<std::size_t>(n));
        bool too_large = false;
        std::string answer = answer_received(c.in, handler, too_large);
        if (!answer.empty()) {
            start_answer(c, std::move(answer), too_large);
            return true;
        }
    }
}

// Sends what is left of the answer; false when the client is done with (or gone).
bool write_answer(Client& c) {
    while (c.sent < c.out.size()) {
        const ssize_t n =
            ::send(c.fd.get(), c.out.data() + c.sent, c.out.size() - c.sent, MSG_NOSIGNAL);
        if (n < 0 && errno == EINTR) continue;
        if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) return true;
        if (n <= 0) return false;
        c.sent += static_cast<std::size_t>(n);
    }
    if (!c.drain_after) return false;
    ::shutdown(c.fd.get(), SHUT_WR);
    c.phase = Client::Phase::Draining;
    c.deadline_ns = now_ns() + kDrainNs;
    return true;
}

// Reads and drops what a client sends after its 431; false once it is done.
bool drain(Client& c) {
    char sink[4096];
    for (;;) {
        const ssize_t n = ::recv(c.fd.get(), sink, sizeof sink, 0);
        if (n < 0 && errno == EINTR) continue;
        if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) return true;
        if (n <= 0) return false;
        c.drained += static_cast<std::size_t>(n);
        if (c.drained > kMaxDrained) return false;
    }
}

// Acts on a client's poll events; false when it is to be closed.
bool serve_client(Client& c, short revents, const HttpServer::Handler& handler) {
    if (revents == 0) return true;
    switch (c.phase) {
        case Client::Phase::Reading:
            return read_request(c, handler) &&
                   (c.phase != Client::Phase::Writing || write_answer(c));
        case Client::Phase::Writing:
            return write_answer(c);
        case Client::Phase::Draining:
            return drain(c);
    }
    return false;
}

void accept_clients(int listener, std::vector<Client>& clients) {
    for (int i = 0; i < 16; ++i) {
        UniqueFd fd(::accept4(listener, nullptr, nullptr, SOCK_CLOEXEC | SOCK_NONBLOCK));
        if (!fd.valid()) return;  // none left, the peer gave up, or out of descriptors
        if (clients.size() >= kMaxClients) clients.erase(clients.begin());
        Client c;
        c.fd = std::move(fd);
        c.deadline_ns = now_ns() + kExchangeDeadlineNs;
        clients.push_back(std::move(c));
    }
}

// How long poll may wait: until the nearest deadline.
int poll_timeout_ms(const std::vector<Client>& clients) {
    if (clients.empty()) return -1;
    std::int64_t nearest = clients.front().deadline_ns;
    for (const Client& c : clients) nearest = std::min(nearest, c.deadline_ns);
    const std::int64_t left = nearest - now_ns();
    return left <= 0 ? 0 : static_cast<int>(left / kNsPerMs + 1);
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

std::string answer_received(std::string_view received, const HttpServer::Handler& handler,
                            bool& too_large) {
    too_large = false;
    if (const std::size_t end = received.find("\r\n\r\n"); end != std::string_view::npos)
        return reply_to(received.substr(0, end + 4), handler);
    if (received.size() <= kMaxRequestHead) return {};
    too_large = true;
    return http_response({431, "text/plain; charset=utf-8", "request too large\n"}, false);
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

Error HttpServer::start(std::string_view listen, Handler handler) {
    Result<Endpoint> endpoint = parse_endpoint(listen, 0);
    if (!endpoint.ok()) return endpoint.error();
    ListenOptions options;
    options.backlog = 16;
    options.reuse_port = false;
    options.nonblocking = true;
    Result<UniqueFd> listener = listen_socket(*endpoint, options);
    if (!listener.ok()) return listener.error();
    listener_ = std::move(listener).value();
    endpoint->set_port(local_port(listener_.get()));
    address_ = endpoint->to_string();
    const int wake = ::eventfd(0, EFD_CLOEXEC);
    if (wake < 0) {
        listener_.reset();
        return from_errno(ErrorCode::Io, errno, "");
    }
    wake_.reset(wake);
    handler_ = std::move(handler);
    thread_ = std::thread([this] { serve(); });
    return Error::none();
}

void HttpServer::stop() noexcept {
    if (!thread_.joinable()) return;
    const std::uint64_t one = 1;
    [[maybe_unused]] const ssize_t n = ::write(wake_.get(), &one, sizeof one);
    thread_.join();
    listener_.reset();
    wake_.reset();
}

// One thread, every client at once: poll over the listener, the stop eventfd and each client,
// each with a deadline, so that no client (dripping, silent, never reading) holds up another
// or stop(). Leaving closes every client.
void HttpServer::serve() noexcept {
    std::vector<Client> clients;
    std::vector<pollfd> fds;
    for (;;) {
        fds.assign({{listener_.get(), POLLIN, 0}, {wake_.get(), POLLIN, 0}});
        for (const Client& c : clients)
            fds.push_back({c.fd.get(),
                           static_cast<short>(c.phase == Client::Phase::Writing ? POLLOUT : POLLIN),
                           0});
        const int rc = ::poll(fds.data(), fds.size(), poll_timeout_ms(clients));
        if (rc < 0 && errno != EINTR) return;
        if (rc < 0) continue;
        if ((fds[1].revents & POLLIN) != 0) return;
        const std::size_t polled = clients.size();
        std::vector<bool> keep(polled, true);
        const std::int64_t now = now_ns();
        for (std::size_t i = 0; i < polled; ++i)
            keep[i] = serve_client(clients[i], fds[i + 2].revents, handler_) &&
                      clients[i].deadline_ns > now;
        for (std::size_t i = polled; i-- > 0;)
            if (!keep[i]) clients.erase(clients.begin() + static_cast<std::ptrdiff_t>(i));
        if ((fds[0].revents & POLLIN) != 0) accept_clients(listener_.get(), clients);
    }
}

}  // namespace mbstorm::net
