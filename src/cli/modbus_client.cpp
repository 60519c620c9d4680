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

std::string ModbusClient::connect(const net::Endpoint& target, int timeout_ms) {
    int fd = net::connect_nonblocking(target);
    if (fd < 0) return std::strerror(-fd);
    fd_.reset(fd);
    auto deadline = Clock::now() + std::chrono::milliseconds(timeout_ms);
    if (!wait_for(fd, POLLOUT, deadline))
        return fmt::format("no connection within {} ms", timeout_ms);
    if (int err = net::socket_error(fd); err != 0) return std::strerror(err);
    net::set_nodelay(fd);
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
    for (std::size_t sent = 0; sent < framed.size;) {
        if (!wait_for(fd_.get(), POLLOUT, deadline)) return "timed out sending the request";
        ssize_t n = ::send(fd_.get(), adu.data() + sent, framed.size - sent, MSG_NOSIGNAL);
        if (n < 0 && (errno == EAGAIN || errno == EINTR)) continue;
        if (n < 0) return fmt::format("send failed: {}", std::strerror(errno));
        sent += static_cast<std::size_t>(n);
    }
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
            buffer_.assign(frame.pdu.begin(), frame.pdu.end());
            if (frame.header.unit_id != unit) {
                return fmt::format("the answer names unit {}, not {}", frame.header.unit_id, unit);
            }
            auto err = codec::decode_response(buffer_, response);
            if (err != codec::CodecError::Ok) {
                return fmt::format("malformed answer ({}): {}", codec::format_hex(buffer_),
                                   codec::error_description(err));
            }
            return {};
        }
        if (!wait_for(fd_.get(), POLLIN, deadline))
            return fmt::format("no answer within {} ms", timeout_ms);
        ssize_t n = ::recv(fd_.get(), chunk.data(), chunk.size(), 0);
        if (n < 0 && (errno == EAGAIN || errno == EINTR)) continue;
        if (n < 0) return fmt::format("receive failed: {}", std::strerror(errno));
        if (n == 0) return "the target closed the connection";
        splitter.feed(codec::Bytes(chunk.data(), static_cast<std::size_t>(n)));
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
    for (std::size_t sent = 0; sent < size;) {
        if (!wait_for(fd_.get(), POLLOUT, deadline)) return "timed out sending the request";
        ssize_t n = ::send(fd_.get(), adu.data() + sent, size - sent, MSG_NOSIGNAL);
        if (n < 0 && (errno == EAGAIN || errno == EINTR)) continue;
        if (n < 0) return fmt::format("send failed: {}", std::strerror(errno));
        sent += static_cast<std::size_t>(n);
    }
    codec::RtuSplitter splitter(codec::RtuSplitter::Direction::Responses);
    codec::TcpFrame frame;
    std::array<std::uint8_t, 512> chunk{};
    for (;;) {
        auto status = splitter.next(frame);
        if (status == codec::RtuSplitter::Status::Fatal) {
            return fmt::format("malformed answer: {}", codec::error_description(splitter.error()));
        }
        if (status == codec::RtuSplitter::Status::Frame) {
            buffer_.assign(frame.pdu.begin(), frame.pdu.end());
            if (frame.header.unit_id != unit) {
                return fmt::format("the answer names unit {}, not {}", frame.header.unit_id, unit);
            }
            auto err = codec::decode_response(buffer_, response);
            if (err != codec::CodecError::Ok) {
                return fmt::format("malformed answer ({}): {}", codec::format_hex(buffer_),
                                   codec::error_description(err));
            }
            return {};
        }
        if (!wait_for(fd_.get(), POLLIN, deadline))
            return fmt::format("no answer within {} ms", timeout_ms);
        ssize_t n = ::recv(fd_.get(), chunk.data(), chunk.size(), 0);
        if (n < 0 && (errno == EAGAIN || errno == EINTR)) continue;
        if (n < 0) return fmt::format("receive failed: {}", std::strerror(errno));
        if (n == 0) return "the target closed the connection";
        splitter.feed(codec::Bytes(chunk.data(), static_cast<std::size_t>(n)));
    }
}

}  // namespace mbstorm::cli
