#include "cli/modbus_client.hpp"

#include <fmt/format.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <chrono>
#include <cstring>

#include "codec/limits.hpp"
#include "codec/mbap.hpp"
#include "codec/rtu_stream.hpp"
#include "codec/values.hpp"

namespace mbstorm::cli {
namespace {

using Clock = std::chrono::steady_clock;

int remaining_ms(Clock::time_point deadline) {
    auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
    return left.count() > 0 ? static_cast<int>(left.count()) : 0;
}

// Waits for `events` on `fd` until `deadline`; false on timeout.
bool wait_for(int fd, short events, Clock::time_point deadline) {
    for (;;) {
        pollfd p{fd, events, 0};
        int rc = ::poll(&p, 1, remaining_ms(deadline));
        if (rc > 0) return true;
        if (rc == 0) return false;
        if (errno != EINTR) return false;
    }
}

}  // namespace

std::string ModbusClient::connect(const net::Endpoint& target, int timeout_ms,
                                  std::shared_ptr<net::TlsContext> tls) {
    int fd = net::connect_nonblocking(target);
    if (fd < 0) return std::strerror(-fd);
    fd_.reset(fd);
    auto deadline = Clock::now() + std::chrono::milliseconds(timeout_ms);
    if (!wait_for(fd, POLLOUT, deadline))
        return fmt::format("no connection within {} ms", timeout_ms);
    if (int err = net::socket_error(fd); err != 0) return std::strerror(err);
    net::set_nodelay(fd);
    if (!tls) return {};
    tls_.emplace(std::move(tls));
    std::array<std::uint8_t, 4096> chunk{};
    for (;;) {
        const net::TlsStatus hs = tls_->handshake();
        if (auto why = send_tls_output(deadline); !why.empty()) return why;
        if (hs == net::TlsStatus::Ok) return {};
        if (hs != net::TlsStatus::WantMore) return "TLS handshake failed: " + tls_->error();
        if (!wait_for(fd, POLLIN, deadline))
            return fmt::format("no TLS handshake within {} ms", timeout_ms);
        ssize_t n = ::recv(fd, chunk.data(), chunk.size(), 0);
        if (n < 0 && (errno == EAGAIN || errno == EINTR)) continue;
        if (n <= 0) return "the target closed the connection during the TLS handshake";
        tls_->feed(chunk.data(), static_cast<std::size_t>(n));
    }
}

std::string ModbusClient::send_tls_output(Deadline deadline) {
    std::vector<std::uint8_t> cipher;
    tls_->take_output(cipher);
    for (std::size_t sent = 0; sent < cipher.size();) {
        if (!wait_for(fd_.get(), POLLOUT, deadline)) return "timed out sending";
        ssize_t n = ::send(fd_.get(), cipher.data() + sent, cipher.size() - sent, MSG_NOSIGNAL);
        if (n < 0 && (errno == EAGAIN || errno == EINTR)) continue;
        if (n < 0) return fmt::format("send failed: {}", std::strerror(errno));
        sent += static_cast<std::size_t>(n);
    }
    return {};
}

std::string ModbusClient::send_all(const std::uint8_t* data, std::size_t size, Deadline deadline) {
    if (tls_) {
        if (tls_->write(data, size) != net::TlsStatus::Ok) return "TLS: " + tls_->error();
        return send_tls_output(deadline);
    }
    for (std::size_t sent = 0; sent < size;) {
        if (!wait_for(fd_.get(), POLLOUT, deadline)) return "timed out sending the request";
        ssize_t n = ::send(fd_.get(), data + sent, size - sent, MSG_NOSIGNAL);
        if (n < 0 && (errno == EAGAIN || errno == EINTR)) continue;
        if (n < 0) return fmt::format("send failed: {}", std::strerror(errno));
        sent += static_cast<std::size_t>(n);
    }
    return {};
}

std::string ModbusClient::receive(std::uint8_t* out, std::size_t capacity, std::size_t& size,
                                  Deadline deadline, int timeout_ms) {
    size = 0;
    // Plaintext the session decrypted earlier is there without the socket.
    if (tls_ && tls_->read(out, capacity, size) == net::TlsStatus::Ok && size > 0) return {};
    if (!wait_for(fd_.get(), POLLIN, deadline))
        return fmt::format("no answer within {} ms", timeout_ms);
    std::array<std::uint8_t, 4096> cipher{};
    std::uint8_t* into = tls_ ? cipher.data() : out;
    ssize_t n = ::recv(fd_.get(), into, tls_ ? cipher.size() : capacity, 0);
    if (n < 0 && (errno == EAGAIN || errno == EINTR)) return {};
    if (n < 0) return fmt::format("receive failed: {}", std::strerror(errno));
    if (n == 0) return "the target closed the connection";
    if (!tls_) {
        size = static_cast<std::size_t>(n);
        return {};
    }
    tls_->feed(cipher.data(), static_cast<std::size_t>(n));
    const net::TlsStatus st = tls_->read(out, capacity, size);
    if (st == net::TlsStatus::Closed) return "the target closed the connection";
    if (st == net::TlsStatus::Failed) return "TLS session refused or broken: " + tls_->error();
    return send_tls_output(deadline);  // a key update's answer, if any
}

std::string ModbusClient::take_answer(const codec::TcpFrame& frame, std::uint8_t unit,
                                      codec::Response& response) {
    buffer_.assign(frame.pdu.begin(), frame.pdu.end());
    if (frame.header.unit_id != unit)
        return fmt::format("the answer names unit {}, not {}", frame.header.unit_id, unit);
    const auto err = codec::decode_response(buffer_, response);
    if (err != codec::CodecError::Ok) {
        return fmt::format("malformed answer ({}): {}", codec::format_hex(buffer_),
                           codec::error_description(err));
    }
    return {};
}

std::string ModbusClient::transact(std::uint8_t unit, codec::Bytes request, int timeout_ms,
                                   codec::Response& response) {
    if (framing_ == codec::Framing::Rtu) return transact_rtu(unit, request, timeout_ms, response);
    const std::uint16_t tid = next_tid_++;
    std::array<std::uint8_t, codec::limits::kMaxTcpAdu> adu{};
    auto framed = codec::encode_tcp_frame(tid, unit, request, adu);
    if (!framed.ok()) return std::string(codec::error_description(framed.error));
    auto deadline = Clock::now() + std::chrono::milliseconds(timeout_ms);
    if (auto why = send_all(adu.data(), framed.size, deadline); !why.empty()) return why;
    codec::MbapSplitter splitter;
    codec::TcpFrame frame;
    std::array<std::uint8_t, 512> chunk{};
    for (;;) {
        auto status = splitter.next(frame);
        if (status == codec::MbapSplitter::Status::Fatal) {
            return fmt::format("malformed answer: {}", codec::error_description(splitter.error()));
        }
        if (status == codec::MbapSplitter::Status::BadProtocolId) continue;  // not Modbus
        if (status == codec::MbapSplitter::Status::Frame) {
            // An answer to an earlier, timed-out request is not ours: skip it.
            if (frame.header.transaction_id != tid) continue;
            return take_answer(frame, unit, response);
        }
        std::size_t n = 0;
        if (auto why = receive(chunk.data(), chunk.size(), n, deadline, timeout_ms); !why.empty())
            return why;
        splitter.feed(codec::Bytes(chunk.data(), n));
    }
}

// RTU over TCP: the request as an RTU frame, and the first whole frame back is its answer
// (one request at a time; a bad CRC is reported, not skipped).
std::string ModbusClient::transact_rtu(std::uint8_t unit, codec::Bytes request, int timeout_ms,
                                       codec::Response& response) {
    std::array<std::uint8_t, codec::limits::kMaxTcpAdu> adu{};
    auto framed = codec::encode_tcp_frame(0, unit, request, adu);
    if (!framed.ok()) return std::string(codec::error_description(framed.error));
    const std::size_t size = codec::mbap_to_rtu_in_place(adu.data(), framed.size);
    auto deadline = Clock::now() + std::chrono::milliseconds(timeout_ms);
    if (auto why = send_all(adu.data(), size, deadline); !why.empty()) return why;
    codec::RtuSplitter splitter(codec::RtuSplitter::Direction::Responses);
    codec::TcpFrame frame;
    std::array<std::uint8_t, 512> chunk{};
    for (;;) {
        auto status = splitter.next(frame);
        if (status == codec::RtuSplitter::Status::Fatal) {
            return fmt::format("malformed answer: {}", codec::error_description(splitter.error()));
        }
        if (status == codec::RtuSplitter::Status::Frame) {
            return take_answer(frame, unit, response);
        }
        std::size_t n = 0;
        if (auto why = receive(chunk.data(), chunk.size(), n, deadline, timeout_ms); !why.empty())
            return why;
        splitter.feed(codec::Bytes(chunk.data(), n));
    }
}

}  // namespace mbstorm::cli
