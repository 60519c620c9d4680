// `mbstorm decode HEX`: prints a TCP, RTU or ASCII frame (or a bare PDU) field by field.
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "cli/commands.hpp"
#include "cli/frame_describe.hpp"
#include "codec/ascii.hpp"
#include "codec/function_code.hpp"
#include "codec/limits.hpp"
#include "codec/mbap.hpp"
#include "codec/rtu.hpp"
#include "codec/values.hpp"

namespace mbstorm::cli {
namespace {

enum class Framing { Auto, Tcp, Rtu, Ascii, Pdu };

struct DecodeOptions {
    std::vector<std::string> hex_words;
    bool tcp = false, rtu = false, ascii = false, pdu = false;
    bool request = false, response = false;
};

struct Decoded {
    std::string title;
    std::vector<FieldRow> rows;
};

// One way of reading the bytes: the tables it shows, and what is wrong with it. Auto-detection
// keeps the reading with the least doubt, so a frame with one bad field is still shown as
// what it most likely is, with that field named.
struct Reading {
    std::string framing;  // "Modbus RTU", for the fault line
    std::vector<Decoded> decoded;
    std::string fault;  // empty: nothing wrong
    int doubt = 0;      // 0 clean frame, 1 one fault in a fitting frame or a clean bare PDU,
                        // 2 bad bare PDU, 3+ misfit
    std::string also;   // another reading as likely, for the user to choose
};

constexpr int kNoFit = 4;

// The bytes in hex, the first 16 of them when there are more (a stderr line stays short).
std::string hex_preview(codec::Bytes bytes) {
    constexpr std::size_t kShown = 16;
    if (bytes.size() <= kShown) return codec::format_hex(bytes);
    return codec::format_hex(bytes.first(kShown)) + " ...";
}

// Tries the directions the user allows; a frame may fit both (FC05/06 echo their request).
std::vector<Direction> directions(const DecodeOptions& o) {
    if (o.request) return {Direction::Request};
    if (o.response) return {Direction::Response};
    return {Direction::Request, Direction::Response};
}

const char* direction_name(Direction d) {
    return d == Direction::Request ? "request" : "response";
}

// The options with only direction `d` allowed.
DecodeOptions one_way(const DecodeOptions& o, Direction d) {
    DecodeOptions only = o;
    only.request = d == Direction::Request;
    only.response = !only.request;
    return only;
}

// When a PDU decodes in neither direction, the one it most likely was: an exception bit or a
// read byte count that matches the length says response.
Direction likely_direction(codec::Bytes pdu, const DecodeOptions& o) {
    if (o.request || o.response) return o.request ? Direction::Request : Direction::Response;
    if (pdu.empty()) return Direction::Request;
    if (pdu[0] & codec::kExceptionBit) return Direction::Response;
    const bool counted_read = codec::response_is(pdu[0], codec::ResponseShape::Bits) ||
                              codec::response_is(pdu[0], codec::ResponseShape::Registers);
    if (counted_read && pdu.size() >= 2 && pdu[1] + 2u == pdu.size()) return Direction::Response;
    return Direction::Request;
}

// Decodes the PDU in each allowed direction, wrapping it with the framing rows. When no
// direction fits, shows the likelier one with its bad field marked and returns its fault.
std::string describe_framed(codec::Bytes pdu, const DecodeOptions& o, const std::string& what,
                            const std::vector<FieldRow>& head, const std::vector<FieldRow>& tail,
                            std::vector<Decoded>& out) {
    auto table = [&](Direction d) {
        Decoded dec;
        dec.rows = head;
        Error fault = describe_pdu(pdu, d, dec.rows);
        dec.rows.insert(dec.rows.end(), tail.begin(), tail.end());
        dec.title = fmt::format("{} {}", what, direction_name(d));
        return std::pair{std::move(fault), std::move(dec)};
    };
    bool any = false;
    for (Direction d : directions(o)) {
        auto [fault, dec] = table(d);
        if (!fault.ok()) continue;
        out.push_back(std::move(dec));
        any = true;
    }
    if (any) return {};
    auto [fault, dec] = table(likely_direction(pdu, o));
    out.push_back(std::move(dec));
    return fault.message();
}

// True when a PDU the bytes end inside has nothing wrong with it so far: it decodes, or fails
// only for running short.
bool sound_so_far(codec::Bytes pdu, Direction d) {
    if (d == Direction::Request) {
        codec::Request request;
        const auto status = codec::decode_request(pdu, request);
        return status.ok() || status.error == codec::CodecError::Truncated;
    }
    codec::Response response;
    const auto error = codec::decode_response(pdu, response);
    return error == codec::CodecError::Ok || error == codec::CodecError::Truncated;
}

// A PDU the bytes end inside: a table for each allowed direction in which it is sound so far
// (a cut PDU decodes in none, so describe_framed alone would show only the likelier one).
void describe_cut_pdu(codec::Bytes pdu, const DecodeOptions& o, const std::string& what,
                      const std::vector<FieldRow>& head, const std::vector<FieldRow>& tail,
                      std::vector<Decoded>& out) {
    const std::size_t before = out.size();
    for (Direction d : directions(o)) {
        if (pdu.empty() || !sound_so_far(pdu, d)) continue;
        describe_framed(pdu, one_way(o, d), what, head, tail, out);
    }
    if (out.size() == before) describe_framed(pdu, o, what, head, tail, out);
}

// The MBAP header's rows, read from an ADU's first 7 bytes.
std::vector<FieldRow> mbap_rows(codec::Bytes adu) {
    const std::uint16_t protocol_id = codec::load_be16(adu.data() + 2);
    return {
        {"Transaction identifier", codec::format_hex(adu.subspan(0, 2)),
         std::to_string(codec::load_be16(adu.data()))},
        {"Protocol identifier", codec::format_hex(adu.subspan(2, 2)),
         protocol_id == 0 ? "0 (Modbus)"
                          : fmt::format("{} (not Modbus: a server discards it)", protocol_id)},
        {"Length", codec::format_hex(adu.subspan(4, 2)),
         fmt::format("{} (unit id + PDU)", codec::load_be16(adu.data() + 4))},
        {"Unit identifier", codec::format_hex(adu.subspan(6, 1)), std::to_string(adu[6])},
    };
}

// The bytes after the last whole ADU (all of them when there is none): an ADU the bytes end
// inside. Shown as far as it goes, header fields and PDU, with the length field marked; fewer
// bytes than a header are one marked row. Returns what is wrong, as one phrase.
std::string describe_cut_adu(codec::Bytes rest, int index, const DecodeOptions& o,
                             std::vector<Decoded>& out) {
    const std::string what =
        fmt::format("Modbus TCP ADU{} ({}, cut short)", index > 1 ? fmt::format(" #{}", index) : "",
                    byte_count(rest.size()));
    if (rest.size() < codec::limits::kMbapHeader) {
        std::string why = fmt::format("{}: an MBAP header needs {}", byte_count(rest.size()),
                                      codec::limits::kMbapHeader);
        out.push_back({what, {{"(part of a header)", codec::format_hex(rest), "<-- BAD: " + why}}});
        return why;
    }
    std::vector<FieldRow> head = mbap_rows(rest);
    std::string why = fmt::format("the length field says {} bytes follow it, {} do",
                                  codec::load_be16(rest.data() + 4), rest.size() - 6);
    head[2].meaning += "  <-- BAD: " + why;
    describe_cut_pdu(rest.subspan(codec::limits::kMbapHeader), o, what, head, {}, out);
    return why;
}

Reading decode_tcp(codec::Bytes bytes, const DecodeOptions& o) {
    Reading reading{"Modbus TCP", {}, {}, 0, {}};
    if (bytes.size() >= 4) {
        std::uint16_t protocol_id = codec::load_be16(bytes.data() + 2);
        if (protocol_id != 0) {
            reading.fault = fmt::format("protocol identifier {} (0x{:04X}): Modbus is 0",
                                        protocol_id, protocol_id);
            reading.doubt = 3;
        }
    }
    // The splitter lets one input hold several pipelined ADUs.
    codec::MbapSplitter splitter;
    splitter.feed(bytes);
    codec::TcpFrame frame;
    int index = 0;
    for (;;) {
        auto status = splitter.next(frame);
        if (status == codec::MbapSplitter::Status::NeedMore) break;
        if (status == codec::MbapSplitter::Status::Fatal) {
            reading.fault =
                fmt::format("bad MBAP header: {}", codec::error_description(splitter.error()));
            reading.doubt = kNoFit;
            return reading;
        }
        ++index;
        std::string what = fmt::format(
            "Modbus TCP ADU{} ({} bytes)",
            index > 1 || splitter.pending() ? fmt::format(" #{}", index) : "", frame.adu.size());
        std::string fault =
            describe_framed(frame.pdu, o, what, mbap_rows(frame.adu), {}, reading.decoded);
        if (!fault.empty() && reading.fault.empty()) {
            reading.fault = index > 1 ? fmt::format("ADU #{}: {}", index, fault) : fault;
            reading.doubt = 1;
        }
    }
    if (index == 0 || splitter.buffered() != 0) {
        const codec::Bytes rest = index == 0 ? bytes : bytes.last(splitter.buffered());
        const std::string cut = describe_cut_adu(rest, index + 1, o, reading.decoded);
        reading.fault = "truncated Modbus TCP frame: " +
                        (index == 0 ? cut
                                    : fmt::format("{} left over after {} complete frame{} ({}): {}",
                                                  byte_count(rest.size()), index,
                                                  index == 1 ? "" : "s", hex_preview(rest), cut));
        // A sound MBAP header whose bytes run short, or bytes left over after sound frames, is
        // one fault in a fitting frame: a better guess than a PDU that fails.
        const bool header_fits =
            bytes.size() >= 7 && codec::load_be16(bytes.data() + 2) == 0 &&
            codec::load_be16(bytes.data() + 4) >= 2 &&
            codec::load_be16(bytes.data() + 4) <= codec::limits::kMaxMbapLength;
        if (index == 0)
            reading.doubt = header_fits ? 1 : kNoFit;
        else
            reading.doubt = reading.doubt == 0 ? 1 : 3;
    }
    return reading;
}

// The whole-frame size the codec's RTU length rule gives a frame starting with `bytes`, read
// in direction `d`; `exact` false when it is a lower bound (a byte count not yet there).
// 0 when the rule cannot tell (a function it has no rule for).
std::size_t rtu_frame_size(codec::Bytes bytes, Direction d, bool& exact) {
    const codec::RtuLength length = d == Direction::Request ? codec::rtu_request_length(bytes)
                                                            : codec::rtu_response_length(bytes);
    exact = length.status == codec::RtuLength::Status::Known;
    return exact || length.status == codec::RtuLength::Status::NeedMore ? length.size : 0;
}

// The bytes read as an RTU frame they end inside: the address and function fit and the
// function's length rule wants more bytes than there are. One table per direction that wants
// more, the PDU as far as it goes, the missing CRC marked. doubt kNoFit when none does.
Reading decode_rtu_cut(codec::Bytes bytes, const DecodeOptions& o) {
    Reading reading{"Modbus RTU", {}, {}, kNoFit, {}};
    constexpr std::size_t kCrcSize = 2;
    if (bytes.size() < 2) return reading;  // no function code: no length rule to ask
    for (Direction d : directions(o)) {
        bool exact = false;
        const std::size_t needed = rtu_frame_size(bytes, d, exact);
        if (needed <= bytes.size()) continue;
        // With only a lower bound the CRC's place is unknown: every byte there is PDU.
        const std::size_t pdu_end =
            exact ? std::min(bytes.size(), needed - kCrcSize) : bytes.size();
        const codec::Bytes pdu = bytes.subspan(1, pdu_end - 1);
        // A direction in which the bytes there are already wrong (a read response's byte count
        // of 0) is no likelier than any other misfit.
        if (!sound_so_far(pdu, d)) continue;
        const codec::Bytes crc = bytes.subspan(pdu_end);
        const std::string why = fmt::format("{}: a {} {} needs {}{}", byte_count(bytes.size()),
                                            codec::function_label(bytes[1]), direction_name(d),
                                            exact ? "" : "at least ", needed);
        std::vector<FieldRow> head{{"Slave address", codec::format_hex(bytes.first(1)),
                                    bytes[0] == 0 ? "0 (broadcast)" : std::to_string(bytes[0])}};
        std::vector<FieldRow> tail{
            {"CRC", codec::format_hex(crc),
             fmt::format("<-- BAD: {} of its 2 bytes there: {}", crc.size(), why)}};
        describe_framed(pdu, one_way(o, d),
                        fmt::format("Modbus RTU frame ({}, cut short)", byte_count(bytes.size())),
                        head, tail, reading.decoded);
        if (reading.fault.empty()) reading.fault = "truncated: " + why;
        reading.doubt = 1;
    }
    return reading;
}

Reading decode_whole_rtu(codec::Bytes bytes, const DecodeOptions& o) {
    Reading reading{"Modbus RTU", {}, {}, 0, {}};
    if (bytes.size() < 4) {
        reading.fault = fmt::format("RTU frame too short: {} (address, function, CRC need 4)",
                                    byte_count(bytes.size()));
        reading.doubt = kNoFit;
        return reading;
    }
    std::uint16_t computed = codec::crc16(bytes.first(bytes.size() - 2));
    std::uint16_t carried =
        static_cast<std::uint16_t>(bytes[bytes.size() - 2] | (bytes[bytes.size() - 1] << 8));
    bool crc_ok = computed == carried;
    std::string crc_meaning = crc_ok ? fmt::format("0x{:04X} correct (low byte first)", carried)
                                     : fmt::format("0x{:04X} WRONG: expected {:02X} {:02X}",
                                                   carried, computed & 0xFF, computed >> 8);
    std::vector<FieldRow> head{{"Slave address", codec::format_hex(bytes.first(1)),
                                bytes[0] == 0 ? "0 (broadcast)" : std::to_string(bytes[0])}};
    std::vector<FieldRow> tail{{"CRC", codec::format_hex(bytes.last(2)), crc_meaning}};
    auto pdu = bytes.subspan(1, bytes.size() - 3);
    std::string what =
        fmt::format("Modbus RTU frame ({} bytes, CRC {})", bytes.size(), crc_ok ? "ok" : "BAD");
    std::string pdu_fault = describe_framed(pdu, o, what, head, tail, reading.decoded);
    if (!crc_ok) {
        reading.fault =
            fmt::format("CRC wrong: expected {:02X} {:02X}, the frame carries {}", computed & 0xFF,
                        computed >> 8, codec::format_hex(bytes.last(2)));
        if (!pdu_fault.empty()) reading.fault += "; and " + pdu_fault;
        reading.doubt = pdu_fault.empty() ? 1 : 3;
    } else if (!pdu_fault.empty()) {
        reading.fault = pdu_fault;
        reading.doubt = 1;
    }
    return reading;
}

// An RTU frame read whole (its last two bytes the CRC) or as cut short, whichever is less in
// doubt; a tie goes to the whole frame, whose CRC could be checked.
Reading decode_rtu(codec::Bytes bytes, const DecodeOptions& o) {
    Reading cut = decode_rtu_cut(bytes, o);
    Reading whole = decode_whole_rtu(bytes, o);
    return cut.doubt < whole.doubt ? cut : whole;
}

Reading decode_bare_pdu(codec::Bytes bytes, const DecodeOptions& o) {
    Reading reading{"a bare PDU", {}, {}, 0, {}};
    if (bytes.empty()) {
        reading.fault = "no bytes to decode";
        reading.doubt = kNoFit;
        return reading;
    }
    reading.fault =
        describe_framed(bytes, o, fmt::format("Modbus PDU ({})", byte_count(bytes.size())), {}, {},
                        reading.decoded);
    // Nothing confirms a bare PDU (no address, CRC or length field): a framed reading with one
    // fault, such as an RTU frame cut short, is as likely (the tie goes to the framing).
    reading.doubt = reading.fault.empty() ? 1 : 2;
    return reading;
}

Reading decode_ascii(std::string text, const DecodeOptions& o) {
    Reading reading{"Modbus ASCII", {}, {}, 0, {}};
    // Shells eat the CR LF; accept a frame without it.
    if (text.size() < 2 || text.substr(text.size() - 2) != "\r\n") text += "\r\n";
    std::array<std::uint8_t, codec::limits::kMaxAsciiAdu> buf{};
    codec::AsciiFrame frame;
    auto err = codec::decode_ascii_frame(std::string_view(text), buf, frame);
    std::string lrc_meaning = "correct";
    if (err == codec::CodecError::BadLrc) {
        // Everything else is sound: show it, with the LRC it should carry.
        auto parsed = codec::parse_hex(std::string_view(text).substr(1, text.size() - 3), buf);
        codec::Bytes binary(buf.data(), parsed.size);
        std::uint8_t expected = codec::lrc(binary.first(binary.size() - 1));
        frame.address = binary[0];
        frame.binary = binary;
        frame.pdu = binary.subspan(1, binary.size() - 2);
        lrc_meaning = fmt::format("WRONG: expected {:02X}", expected);
        reading.fault = fmt::format("LRC wrong: expected {:02X}, the frame carries {:02X}",
                                    expected, binary.back());
        reading.doubt = 1;
    } else if (err != codec::CodecError::Ok) {
        reading.fault = fmt::format("bad ASCII frame: {}", codec::error_description(err));
        reading.doubt = kNoFit;
        return reading;
    }
    std::vector<FieldRow> head{
        {"Start", ":", "frame start"},
        {"Slave address", codec::format_hex(frame.binary.first(1)), std::to_string(frame.address)}};
    std::vector<FieldRow> tail{{"LRC", codec::format_hex(frame.binary.last(1)), lrc_meaning},
                               {"End", "CR LF", "frame end"}};
    std::string pdu_fault = describe_framed(
        frame.pdu, o, fmt::format("Modbus ASCII frame ({} characters)", text.size()), head, tail,
        reading.decoded);
    if (!pdu_fault.empty()) {
        reading.fault += (reading.fault.empty() ? "" : "; and ") + pdu_fault;
        reading.doubt = std::max(reading.doubt, 1);
    }
    return reading;
}

// Reads the bytes every way they could be framed and keeps the most plausible reading; on a
// tie, TCP before RTU before a bare PDU, and a sound bare PDU passed over is named.
Reading decode_guessing(codec::Bytes bytes, const DecodeOptions& o) {
    Reading best = decode_tcp(bytes, o);
    if (best.doubt == 0) return best;
    Reading rtu = decode_rtu(bytes, o);
    if (rtu.doubt < best.doubt) best = std::move(rtu);
    if (best.doubt == 0) return best;
    Reading bare = decode_bare_pdu(bytes, o);
    if (bare.doubt < best.doubt) return bare;
    if (bare.fault.empty() && !bare.decoded.empty())
        best.also = fmt::format("the same bytes are also a sound {}: --pdu shows it",
                                bare.decoded.front().title);
    return best;
}

int run_decode(const DecodeOptions& o) {
    std::string text;
    for (const auto& w : o.hex_words) text += (text.empty() ? "" : " ") + w;
    Framing framing = o.tcp     ? Framing::Tcp
                      : o.rtu   ? Framing::Rtu
                      : o.ascii ? Framing::Ascii
                      : o.pdu   ? Framing::Pdu
                                : Framing::Auto;
    if (framing == Framing::Auto && !text.empty() && text.front() == ':') framing = Framing::Ascii;

    Reading reading;
    if (framing == Framing::Ascii) {
        reading = decode_ascii(text, o);
    } else {
        std::array<std::uint8_t, 4096> buf{};
        auto parsed = codec::parse_hex(text, buf);
        if (parsed.error == codec::CodecError::BufferTooSmall) {
            fmt::print(stderr,
                       "mbstorm decode: too many bytes: more than {} (the longest Modbus frame is "
                       "{})\n",
                       buf.size(), codec::limits::kMaxRtuAdu);
            return kExitUsage;
        }
        if (!parsed.ok()) {
            fmt::print(stderr, "mbstorm decode: bad hex at character {}: {}\n", parsed.position + 1,
                       parsed.error == codec::CodecError::OddHexLength ? "odd number of hex digits"
                                                                       : "not a hex digit");
            return kExitUsage;
        }
        codec::Bytes bytes(buf.data(), parsed.size);
        switch (framing) {
            case Framing::Tcp:
                reading = decode_tcp(bytes, o);
                break;
            case Framing::Rtu:
                reading = decode_rtu(bytes, o);
                break;
            case Framing::Pdu:
                reading = decode_bare_pdu(bytes, o);
                break;
            default:
                reading = decode_guessing(bytes, o);
        }
    }
    // Bytes that fit no framing are one line, whatever a misfit reading managed to show; a
    // framing the user named is shown as far as it goes.
    if (framing == Framing::Auto && reading.doubt >= kNoFit) reading.decoded.clear();
    for (std::size_t i = 0; i < reading.decoded.size(); ++i) {
        fmt::print("{}{}:\n{}", i ? "\n" : "", reading.decoded[i].title,
                   render_rows(reading.decoded[i].rows));
    }
    if (reading.fault.empty()) return kExitOk;
    std::fflush(stdout);
    if (reading.decoded.empty()) {
        fmt::print(stderr, "mbstorm decode: {}\n", reading.fault);
        return kExitUsage;
    }
    fmt::print(stderr, "mbstorm decode: {}{}: {}\n", framing == Framing::Auto ? "read as " : "",
               reading.framing, reading.fault);
    if (!reading.also.empty()) fmt::print(stderr, "mbstorm decode: {}\n", reading.also);
    return kExitFailed;
}

}  // namespace

void add_decode_command(CLI::App& app, Action& action) {
    auto opts = std::make_shared<DecodeOptions>();
    auto* cmd = app.add_subcommand("decode", "Print a Modbus frame field by field");
    cmd->add_option("hex", opts->hex_words,
                    "Frame as hex, spaces optional (e.g. \"01 03 00 00 00 0A C5 CD\")")
        ->required();
    auto* tcp = cmd->add_flag("--tcp", opts->tcp, "Modbus TCP ADU(s) with MBAP header");
    auto* rtu = cmd->add_flag("--rtu", opts->rtu, "RTU frame: address, PDU, CRC-16");
    auto* ascii = cmd->add_flag("--ascii", opts->ascii, "ASCII frame: ':' hex LRC CR LF");
    auto* pdu = cmd->add_flag("--pdu", opts->pdu, "a bare PDU (function code first)");
    tcp->excludes(rtu, ascii, pdu);
    rtu->excludes(ascii, pdu);
    ascii->excludes(pdu);
    auto* req = cmd->add_flag("--request", opts->request, "decode as a request only");
    auto* rsp = cmd->add_flag("--response", opts->response, "decode as a response only");
    req->excludes(rsp);
    cmd->callback([opts, &action] { action = [opts] { return run_decode(*opts); }; });
}

}  // namespace mbstorm::cli
