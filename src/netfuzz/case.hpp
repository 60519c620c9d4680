// One fuzz case: a short script of sends on one or more connections, plus the labels that
// findings are deduplicated by. Expectations are NOT stored: the oracle derives them from the
// bytes sent (the codec says what a conforming server must answer), so a case replays from
// its bytes alone.
#pragma once

#include <cstdint>
#include <string_view>
#include <vector>

#include "codec/framing.hpp"
#include "codec/pdu.hpp"

namespace mbstorm::netfuzz {

// How a case was made. Findings are deduplicated by (oracle, function code, class).
enum class MutationClass : std::uint8_t {
    ValidLimits,        // well-formed requests with values at the limits
    InvalidValues,      // out-of-spec values: quantity 0/max+1, bad byte counts, bad coil values
    UnknownFunction,    // function codes the spec does not define (0-255)
    UnitId,             // unit ids 0, 0xF7, 0xFF, random
    TransactionId,      // special transaction ids (0, 0x7FFF, 0x8000, 0xFFFF, duplicates)
    ProtocolId,         // protocol id != 0 (must be discarded)
    MbapLength,         // length 0, 1, > 254, too short, too long
    TrailingBytes,      // PDU with extra bytes inside a consistent length
    Truncated,          // frame cut short, then the connection is half-closed
    Split,              // one frame split across two sends at every offset
    Coalesced,          // many frames in one send
    Drip,               // one byte per send with gaps
    HalfClose,          // partial frame then shutdown(SHUT_WR)
    HalfCloseAnswered,  // complete frames then shutdown(SHUT_WR): every one is still owed
    BurstSplit,         // a pipelined burst split inside one of its frames, the rest coalesced
    PartialHold,        // a started frame held open while another connection probes
    ExceptionStall,     // a request owed an exception, then another connection probes
    Flood,              // a bounded burst of connections
    StatefulSame,       // write then read back on the same connection
    StatefulCross,      // write on one connection, read back on another
    RecordedMutation,   // bit flips and field splices of recorded valid traffic
    NaiveRandom,        // baseline: random PDU bytes in a valid MBAP frame
    // The other transport spoken to the port (netfuzz/cross_transport.hpp): the server must
    // refuse or close that connection and go on serving the others.
    PlaintextToTls,      // plain Modbus/TCP on a fresh TCP connection to a TLS port
    PlaintextInSession,  // plain Modbus/TCP between the records of an established TLS session
    TlsToPlain,          // a TLS ClientHello (and more records) to a plain Modbus/TCP port
    BadChecksum,         // RTU/ASCII: a frame with a wrong CRC or LRC (to be discarded)
    BrokenSilence,       // serial RTU: a frame split by a gap longer than 1.5 characters
    NoSilence,           // serial: two frames without the 3.5-character silence between them
    Noise,               // serial: noise bytes on the line before a frame
    // From the device model (netfuzz/device_model.hpp): requests inside the target's map, so
    // that the code behind each address check runs.
    InMap,    // a request inside the map, valid but for at most one field
    MapEdge,  // each edge of each valid range: first, last, one before, one past
    // Coverage-guided (fuzz --coverage, netfuzz/coverage_map.hpp): a case that reached new
    // edges of the target, its frames' fields mutated (set to constants the target compared
    // them against, bit flips, arithmetic, splices).
    CoverageMutation,
    // Asked by the campaign of a target whose silences do not repeat: one valid request sent
    // again and again, each answer awaited. A target that leaves some unanswered drops
    // requests at random (one defect, however many requests it has dropped).
    Repeated,
    Count
};

std::string_view class_name(MutationClass c) noexcept;
// Classes whose faults lie in how bytes arrive (splits, drips, half-closes, lying lengths,
// floods) rather than in what a request asks: their root causes are keyed by the class.
bool is_transport_class(MutationClass c) noexcept;
// Classes whose verdict rests on a silence on a serial line: how long the slave saw it is up to
// the scheduler (a busy machine may deliver both sides of a gap in one read).
bool depends_on_line_timing(MutationClass c) noexcept;
bool class_from_name(std::string_view name, MutationClass& out) noexcept;

enum class Op : std::uint8_t {
    Send,           // write `bytes` on `conn` after `delay_us`
    ShutdownWrite,  // half-close `conn`
    Await,          // wait until every request sent on `conn` so far is answered
    Flood,          // open `count` extra connections at once, one probe each, close them
    SideProbe,      // probe on a fresh connection now, while the case's connections are as they
                    // are: a slow answer means the case stalls other clients too
};

// A step's operation as finding and corpus files name it ("send", "shutdown-write", ...).
std::string_view op_name(Op op) noexcept;
bool op_from_name(std::string_view name, Op& out) noexcept;

struct Step {
    Op op = Op::Send;
    std::uint8_t conn = 0;
    std::uint32_t delay_us = 0;
    std::uint16_t count = 0;  // Flood only
    std::vector<std::uint8_t> bytes;
};

struct Case {
    MutationClass cls = MutationClass::ValidLimits;
    std::uint8_t function = 0;  // the function code it is about
    std::uint64_t number = 0;   // its place in the run (1-based; 0: not from a run)
    std::vector<Step> steps;

    // True when the case is a single send on one connection of complete, well-framed ADUs:
    // it can then share a pipelined connection with other cases.
    bool pipelinable = false;
    std::uint8_t connections() const noexcept;
};

// The PDU of `request` as the codec's encoder writes it, unchecked: a case may get a field
// wrong on purpose (a coil value, padding bits), and the bytes are then still the codec's.
std::vector<std::uint8_t> encode_pdu(const codec::Request& request);

// The payload bytes of registers: each value big-endian, as a request carries them.
std::vector<std::uint8_t> register_bytes(const std::vector<std::uint16_t>& values);

// One frame around `pdu` in the given framing: MBAP (header written by the codec), RTU (unit,
// PDU, CRC-16; `tid` unused) or ASCII (':' hex of unit, PDU and LRC, CR LF; `tid` unused). Any
// size: a mutation may have made a PDU the codec's encoder would refuse; lengths that lie are
// set afterwards.
std::vector<std::uint8_t> frame_pdu(const std::vector<std::uint8_t>& pdu, std::uint16_t tid,
                                    std::uint8_t unit,
                                    codec::Framing framing = codec::Framing::Mbap);

}  // namespace mbstorm::netfuzz
