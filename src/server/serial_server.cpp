#include "server/serial_server.hpp"

#include <signal.h>

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>
#include <ctime>
#include <limits>
#include <thread>
#include <utility>

#include "codec/ascii.hpp"
#include "codec/limits.hpp"
#include "codec/rtu.hpp"
#include "codec/serial_frame_reader.hpp"
#include "net/clock.hpp"
#include "server/run.hpp"
#include "slave/data_model.hpp"
#include "slave/handler.hpp"

namespace mbstorm::server {
namespace {

constexpr std::int64_t kStopCheckNs = 100'000'000;
constexpr std::int64_t kSimulateEveryNs = 50'000'000;

void add(std::atomic<std::uint64_t>& c, std::uint64_t n = 1) noexcept {
    c.fetch_add(n, std::memory_order_relaxed);
}

}  // namespace

SerialServer::SerialServer(SerialServerConfig config)
    : config_(std::move(config)),
      faults_(config_.faults, 0, static_cast<std::uint64_t>(net::now_ns())) {}

Error SerialServer::open() {
    if (config_.units == nullptr)
        return Error(ErrorCode::InvalidInput, "the serial server needs its unit models");
    return port_.open(config_.device, config_.line);
}

std::string SerialServer::describe() const {
    return fmt::format("{} at {} {}", config_.device, net::describe(config_.line),
                       codec::framing_name(config_.framing));
}

SerialServerStats SerialServer::stats() const noexcept {
    auto get = [](const std::atomic<std::uint64_t>& c) {
        return c.load(std::memory_order_relaxed);
    };
    const auto& c = counters_;
    return {get(c.requests),      get(c.responses),   get(c.exceptions),    get(c.broadcasts),
            get(c.not_addressed), get(c.bad_checks),  get(c.broken_frames), get(c.noise_bytes),
            get(c.fault_delayed), get(c.fault_silent)};
}

Error SerialServer::run(const std::atomic<bool>& stop) {
    const bool rtu = config_.framing == codec::Framing::Rtu;
    const std::int64_t char_gap = net::intercharacter_timeout_ns(config_.line);
    const std::int64_t silence =
        rtu ? net::interframe_silence_ns(config_.line) : config_.ascii_timeout_ns;
    codec::SerialFrameReader reader(config_.framing, codec::SerialFrameReader::Reads::Requests);
    std::optional<slave::Simulator> simulator;
    if (!config_.simulated.empty()) simulator.emplace(config_.simulated, *config_.units);
    const std::int64_t start = net::now_ns();
    std::int64_t next_simulation = start;
    std::array<std::uint8_t, 512> chunk{};
    codec::SerialFrame frame;
    while (!stop.load(std::memory_order_relaxed)) {
        if (simulator && net::now_ns() >= next_simulation) {
            simulator->update(static_cast<std::uint64_t>(net::now_ns() - start));
            next_simulation += kSimulateEveryNs;
        }
        const bool waiting = reader.pending();
        bool silent = false;
        if (port_.wait_readable(waiting ? silence : kStopCheckNs)) {
            const std::int64_t previous = port_.last_byte_received_ns();
            const ssize_t n = port_.read_some(chunk.data(), chunk.size());
            if (n < 0) {
                // A pty whose other end is closed reads EIO until it is reopened: wait.
                if (n == -EIO) {
                    std::this_thread::sleep_for(std::chrono::milliseconds(20));
                    continue;
                }
                return from_errno(ErrorCode::Io, static_cast<int>(-n), "reading " + config_.device);
            }
            if (n == 0) continue;
            const bool gap = rtu && waiting && port_.last_byte_received_ns() - previous > char_gap;
            reader.feed(codec::Bytes(chunk.data(), static_cast<std::size_t>(n)), gap);
        } else {
            silent = waiting;
        }
        for (;;) {
            const auto r = reader.next(frame, silent);
            if (r.kind == codec::SerialFrameReader::Result::Kind::None) break;
            if (r.kind == codec::SerialFrameReader::Result::Kind::Error) {
                if (r.error == codec::CodecError::BadCrc || r.error == codec::CodecError::BadLrc)
                    add(counters_.bad_checks);
                else
                    add(counters_.broken_frames);
                add(counters_.noise_bytes, r.dropped);
                continue;
            }
            serve_frame(frame.address, frame.pdu);
        }
    }
    return Error::none();
}

void SerialServer::serve_frame(std::uint8_t address, codec::Bytes pdu) {
    if (address != 0 && config_.only_unit && *config_.only_unit != address) {
        add(counters_.not_addressed);
        return;
    }
    add(counters_.requests);
    std::array<std::uint8_t, slave::kMinOutput> out{};
    slave::HandleResult r;
    // Broadcasts are never answered: nothing to fault.
    const slave::FaultDecision fault =
        faults_.enabled() && address != 0 ? faults_.decide() : slave::FaultDecision{};
    switch (fault.action) {
        case slave::FaultDecision::Action::Drop:
        case slave::FaultDecision::Action::NoAnswer:
            add(counters_.fault_silent);
            return;
        case slave::FaultDecision::Action::Exception:
            out[0] = static_cast<std::uint8_t>((pdu.empty() ? 0 : pdu[0]) | codec::kExceptionBit);
            out[1] = static_cast<std::uint8_t>(fault.exception);
            r.size = 2;
            r.outcome = slave::Outcome::Exception;
            r.exception = fault.exception;
            break;
        case slave::FaultDecision::Action::Answer:
            r = slave::handle_request(address, pdu, *config_.units, out);
            break;
    }
    if (faults_.enabled() && address != 0) {
        const auto now = static_cast<std::uint64_t>(net::now_ns());
        const std::uint64_t release = faults_.held_until(now + fault.delay_ns);
        if (release > now) {
            add(counters_.fault_delayed);
            net::sleep_until_ns(static_cast<std::int64_t>(release));  // the bus waits too
        }
    }
    if (address == 0) add(counters_.broadcasts);
    if (r.outcome == slave::Outcome::NoResponse || r.size == 0) {
        if (address != 0) add(counters_.not_addressed);
        return;
    }
    const codec::Bytes answer(out.data(), r.size);
    std::array<std::uint8_t, codec::limits::kMaxAsciiAdu> frame{};
    const bool rtu = config_.framing == codec::Framing::Rtu;
    const auto enc = rtu ? codec::encode_rtu_frame(address, answer, frame)
                         : codec::encode_ascii_frame(address, answer, frame);
    if (!enc.ok()) return;
    // RTU: the master must hear 3.5 characters of silence before the answer.
    const std::int64_t silence = rtu ? net::interframe_silence_ns(config_.line) : 0;
    if (port_.send_frame(frame.data(), enc.size, silence) != 0) return;
    add(counters_.responses);
    if (r.outcome == slave::Outcome::Exception) add(counters_.exceptions);
}

namespace {

std::string format_serial_stats(const SerialServerStats& s) {
    return fmt::format(
        "{} requests, {} responses ({} exceptions), {} broadcasts, {} not addressed, {} CRC/LRC "
        "errors, {} broken frames ({} bytes dropped), faults: {} delayed, {} unanswered",
        s.requests, s.responses, s.exceptions, s.broadcasts, s.not_addressed, s.bad_checks,
        s.broken_frames, s.noise_bytes, s.fault_delayed, s.fault_silent);
}

}  // namespace

Error run_serial_until_signal(SerialServer& server, bool print_stats, double max_seconds,
                              std::FILE* out) {
    block_stop_signals();
    std::atomic<bool> stop{false}, finished{false};
    Error failure;
    std::thread worker([&] {
        failure = server.run(stop);
        finished = true;
    });
    sigset_t set;
    sigemptyset(&set);
    sigaddset(&set, SIGINT);
    sigaddset(&set, SIGTERM);
    const std::int64_t start = net::now_ns();
    std::int64_t next = start + net::kNsPerSec;
    const std::int64_t end = max_seconds > 0 ? start + static_cast<std::int64_t>(max_seconds * 1e9)
                                             : std::numeric_limits<std::int64_t>::max();
    while (!finished) {
        std::int64_t now = net::now_ns();
        if (now >= end) break;
        // Short waits: a server that failed on its own ends the run too (and -d 300ms ends at
        // 300 ms, not at the next statistics line).
        const std::int64_t wait = std::min({next > now ? next - now : 0, kStopCheckNs, end - now});
        timespec ts{static_cast<time_t>(wait / net::kNsPerSec),
                    static_cast<long>(wait % net::kNsPerSec)};
        const int sig = sigtimedwait(&set, nullptr, &ts);
        if (sig == SIGINT || sig == SIGTERM) break;
        if (net::now_ns() >= next) {
            if (print_stats) {
                std::fprintf(out, "%s\n", format_serial_stats(server.stats()).c_str());
                std::fflush(out);
            }
            next += net::kNsPerSec;
        }
    }
    stop = true;
    worker.join();
    std::fprintf(out, "serial: %s\n", format_serial_stats(server.stats()).c_str());
    std::fflush(out);
    return failure;
}

}  // namespace mbstorm::server
