// The oracles: what a conforming Modbus TCP server must answer to a given request, and a
// verdict on what the target actually answered. Expectations come from the codec (one place
// per fact): decode_request says whether a PDU is valid and, if not, the exception a server
// owes (v1.1b3 precedence: 01, then 03, then 02).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "codec/framing.hpp"
#include "codec/mbap.hpp"
#include "codec/pdu.hpp"
#include "netfuzz/case.hpp"
#include "netfuzz/rules.hpp"

namespace mbstorm::netfuzz {

enum class Oracle : std::uint8_t {
    None,
    Crash,              // the target stopped accepting connections
    Hang,               // no answer in time on an open connection
    UnexpectedClose,    // close or reset while a well-formed request was unanswered
    MalformedResponse,  // undecodable, or does not match the request
    SpecDeviation,      // wrong exception, normal answer to an invalid request, ...
    Count
};

std::string_view oracle_name(Oracle o) noexcept;  // "crash", "spec-deviation", ...
bool oracle_from_name(std::string_view name, Oracle& out) noexcept;

struct Verdict {
    Oracle oracle = Oracle::None;
    // What was violated, worded so that the same fault gives the same rule whatever the case
    // (no transaction ids, addresses or values): with the oracle, a finding's root-cause
    // identity. The function code is part of it only where the fault is tied to it.
    std::string rule;
    int culprit_fc = -1;    // function code of the request at fault (-1: none, or not framed)
    std::string summary;    // one line
    std::string expected;   // what a conforming server does
    std::string seen;       // what the target did
    int culprit_unit = -1;  // unit id of the request at fault
    explicit operator bool() const noexcept { return oracle != Oracle::None; }
};

// What the fuzzer learned about the target before fuzzing.
struct TargetProfile {
    std::uint8_t unit = 1;                // the unit id the target answers
    std::vector<std::uint8_t> probe_pdu;  // a request the target answers normally
    // Per function code: the target answers its canonical valid request with 01 (unsupported)
    // or answers normally although the codec does not know it (a vendor extension).
    std::array<bool, 256> unsupported{};
    std::array<bool, 256> extended{};
    // The canonical valid request of this function code drew no answer at discovery while the
    // stream went on: the campaign looks at it alone first.
    std::array<bool, 256> silent{};
    // It drops requests pipelined behind one it answers with an exception (libmodbus flushes
    // its socket after an exception): such requests are sent only after that answer.
    bool drops_after_exception = false;
    // How frames are framed (the connector's): MBAP, or RTU/ASCII, where there are no
    // transaction ids, so one request is in flight per link and its answer is the next frame.
    codec::Framing framing = codec::Framing::Mbap;
    // A serial line: silences delimit frames, unit 0 is a broadcast nobody answers.
    bool serial_line = false;
    // Per table (codec::Table order): addresses a read of one item alone was refused at with
    // 02 while learning the map (each learned range's neighbours). A read that covers one of
    // them owes 02 as well: answered normally, it is a deviation.
    std::array<std::vector<std::uint16_t>, 4> unmapped{};
    // Asked once (campaign.cpp): it closes on a frame of the wrong length by itself, before
    // anything follows it, as it may close on any request it cannot use (pymodbus 3.0). Such a
    // close is then close-with-request-pending/invalid-request, not a lost stream: see
    // understood_by, used by the campaign and by replay alike.
    bool refuses_length_mismatch = false;
    // It serves one connection at a time (the next waits in the listen backlog): cases that
    // need two at once are not sent, pipelined batches use one lane, and a case's connections
    // are closed before a fresh probe (which would otherwise wait behind them).
    bool one_connection = false;
    // It answers frames with a protocol id other than 0 (found at the first looks): such a frame
    // reaches its function's handler, so a death or a whole-server hang it causes is named by
    // that handler, as the same request with protocol id 0 would be.
    bool answers_protocol_id = false;
    // The holding register whose value tells a restart where there are no sentinels
    // (state_marker.hpp), so that replay watches the same way. -1: none.
    std::int32_t marker_address = -1;
};

// Addresses (holding registers and coils) that only stateful cases write; every other write
// the fuzzer generates or mutates is moved out of this range (see relocate_writes), and
// stateful cases run alone, so a read-back that differs is the target's fault. The user may
// give the whole address map (--state-range all): nothing is relocated then, and stateful
// cases still run alone, between batches.
inline constexpr std::uint16_t kStateBase = 0x6000;
inline constexpr std::uint16_t kStateSpan = 0x1000;

struct StateRange {
    std::uint16_t base = kStateBase;
    std::uint32_t span = kStateSpan;  // 0x10000: the whole map
    bool contains(std::uint32_t a) const noexcept { return a >= base && a < base + span; }
    bool whole_map() const noexcept { return base == 0 && span >= 0x10000; }
};

// What the fuzzer expects for one request frame it sent.
enum class Expect : std::uint8_t {
    Answer,        // a response must come
    MayBeSilent,   // e.g. a unit id the target may not serve
    MustBeSilent,  // protocol id != 0: the frame is to be discarded
};

struct RequestInfo {
    codec::MbapHeader header;
    codec::Bytes pdu;
    codec::Request request;
    codec::RequestStatus status;  // status.exception != None: the exception owed
    Expect expect = Expect::Answer;
    // Why a conforming reader discards the frame ("bad-crc", "broken-frame", "broadcast", ...;
    // RTU and ASCII only): an answer to it is a deviation named after it.
    std::string_view discard;
};

// What kind of request a frame is, for root-cause rules: "valid", "invalid" (the codec owes
// an exception) or "unknown-fc".
std::string_view request_kind(const RequestInfo& info) noexcept;

// The words a root-cause rule uses for the request at fault: "fc0F" (its handler, valid
// request or not), "unknown-fc" (one default branch, whatever the code), or the class name for
// transport mutations (the fault is in how bytes arrived, not in what was asked) and when
// there is no request.
std::string culprit_text(MutationClass cls, const RequestInfo* rq);

// True when a conforming server owes this request an exception (or the target said it does
// not support its function code).
bool owes_exception(const RequestInfo& info, const TargetProfile& profile) noexcept;

// A request whose MBAP length is consistent but whose PDU is shorter or longer than its
// function code implies (or whose function code gives no length at all). A server that frames
// by the MBAP length answers it and goes on; one that frames by the function code takes bytes
// of the next frame or waits for bytes that never come. Whatever the stream then shows (a
// close, silence, an answer with a transaction id nobody sent), it is that one root cause
// (kStreamLostRule: rule texts are named in netfuzz/rules.hpp).
bool pdu_length_mismatch(const RequestInfo& info) noexcept;

// A verdict as what is known of the target explains it (TargetProfile::refuses_length_mismatch).
Verdict understood_by(const TargetProfile& profile, Verdict v);

// Fills `info` for one complete, well-framed request ADU.
void describe_request(codec::Bytes adu, const TargetProfile& profile, RequestInfo& info) noexcept;

// Judges one response frame (already cut by its MBAP length) against its request.
Verdict judge_response(const RequestInfo& rq, codec::Bytes response_adu,
                       const TargetProfile& profile);

// Rewrites the address fields of a write request ADU (05, 06, 0F, 10, 16, 17) so that it
// stays out of the stateful range. Works on raw bytes (mutated frames included).
void relocate_writes(std::uint8_t* adu, std::size_t size, const StateRange& state) noexcept;

// Reads-after-writes checking for one case: remembers acknowledged writes in the stateful
// range and compares later reads of the same addresses.
class Shadow {
  public:
    struct Event {
        const RequestInfo* request;
        std::int64_t sent_ns;
        std::int64_t answered_ns;  // 0: no answer
        codec::Bytes response_pdu;
        std::uint8_t conn = 0;  // the connection it went out on
    };
    // Events in any order; returns the first mismatch, read on the writer's own connection
    // first. A value only other connections read wrong is a fault of its own
    // (read-after-write-mismatch-other-connection). The writer's function code ends the rule:
    // a mask write that stores the wrong value and a plain write that does are two faults.
    static Verdict check(std::vector<Event>& events, const StateRange& state);
};

std::string hex(codec::Bytes bytes, std::size_t max = 64);

}  // namespace mbstorm::netfuzz
