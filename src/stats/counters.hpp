// Outcome counters for one operation (or a whole run): how every transaction ended, plus
// traffic totals. Plain uint64 arrays: cheap to bump on the hot path, cheap to merge.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string_view>

namespace mbstorm::stats {

// How one transaction ended. Exception responses are one outcome; their exception code is
// counted separately in OutcomeCounters::exceptions (stats knows no Modbus names — the
// codec layer owns those).
enum class Outcome : std::uint8_t {
    Ok,                // valid, matching response
    Exception,         // exception response (function | 0x80); see exceptions[code]
    Timeout,           // no response within the timeout
    ConnectionClosed,  // connection reset or closed while the request was outstanding
    ConnectFailed,     // the request could not be sent because connecting failed
    Malformed,         // the response did not decode
    UnknownId,         // stray response: transaction id nobody is waiting for
    DuplicateId,       // stray response: a second answer for an id already answered
    WrongUnitId,       // unit id differs from the request's
    WrongFunction,     // function code differs from the request's
    ValueMismatch,     // read-after-write check saw a different value
    FramingError,      // the answer stream lost MBAP framing (length 0, 1 or > 254, garbage):
                       // the connection was reset with the request outstanding
    CrcError,          // RTU (over TCP or serial) or ASCII: an answer's CRC/LRC failed
};
inline constexpr std::size_t kOutcomeCount = 13;

// snake_case name used in JSON and console output, e.g. "connection_closed".
constexpr std::string_view outcome_name(Outcome outcome) noexcept {
    constexpr std::array<std::string_view, kOutcomeCount> kNames = {"ok",
                                                                    "exception",
                                                                    "timeout",
                                                                    "connection_closed",
                                                                    "connect_failed",
                                                                    "malformed",
                                                                    "unknown_id",
                                                                    "duplicate_id",
                                                                    "wrong_unit_id",
                                                                    "wrong_function",
                                                                    "value_mismatch",
                                                                    "framing_error",
                                                                    "crc_error"};
    const auto i = static_cast<std::size_t>(outcome);
    return i < kOutcomeCount ? kNames[i] : std::string_view{"unknown"};
}
constexpr bool is_error(Outcome outcome) noexcept {
    return outcome != Outcome::Ok;
}
// A stray response answers no transaction (its id is unknown or already answered): counted,
// but never as a transaction, so throughput and error rates stay per transaction.
constexpr bool is_stray(Outcome outcome) noexcept {
    return outcome == Outcome::UnknownId || outcome == Outcome::DuplicateId;
}

struct OutcomeCounters {
    std::array<std::uint64_t, kOutcomeCount> outcomes{};  // indexed by Outcome
    std::array<std::uint64_t, 256> exceptions{};          // indexed by exception code byte
    std::uint64_t transactions_sent = 0;
    std::uint64_t bytes_sent = 0;
    std::uint64_t bytes_received = 0;

    void record(Outcome outcome) noexcept { ++outcomes[static_cast<std::size_t>(outcome)]; }
    void record_exception(std::uint8_t code) noexcept {
        ++outcomes[static_cast<std::size_t>(Outcome::Exception)];
        ++exceptions[code];
    }
    std::uint64_t count(Outcome outcome) const noexcept {
        return outcomes[static_cast<std::size_t>(outcome)];
    }
    std::uint64_t ok() const noexcept { return count(Outcome::Ok); }
    // Transactions that ended (ok + failed); stray responses are not transactions.
    std::uint64_t completed() const noexcept {
        std::uint64_t sum = 0;
        for (std::size_t i = 0; i < kOutcomeCount; ++i)
            if (!is_stray(static_cast<Outcome>(i))) sum += outcomes[i];
        return sum;
    }
    // Transactions that ended with anything but a valid, matching response.
    std::uint64_t errors() const noexcept { return completed() - ok(); }
    std::uint64_t stray_responses() const noexcept {
        return count(Outcome::UnknownId) + count(Outcome::DuplicateId);
    }

    void add(const OutcomeCounters& other) noexcept {
        for (std::size_t i = 0; i < kOutcomeCount; ++i) outcomes[i] += other.outcomes[i];
        for (std::size_t i = 0; i < exceptions.size(); ++i) exceptions[i] += other.exceptions[i];
        transactions_sent += other.transactions_sent;
        bytes_sent += other.bytes_sent;
        bytes_received += other.bytes_received;
    }
    void reset() noexcept { *this = OutcomeCounters{}; }
};

}  // namespace mbstorm::stats
