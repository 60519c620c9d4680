// `mbstorm decode HEX`: prints a TCP, RTU or ASCII frame (or a bare PDU) field by field.
#include <fmt/format.h>

#include <array>
#include <cstdio>
#include <string>
#include <vector>

#include "cli/commands.hpp"
#include "cli/frame_describe.hpp"
#include "codec/ascii.hpp"
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

// Tries the directions the user allows; a frame may fit both (FC05/06 echo their request).
std::vector<Direction> directions(const DecodeOptions& o) {
    if (o.request) return {Direction::Request};
    if (o.response) return {Direction::Response};
    return {Direction::Request, Direction::Response};
}

const char* direction_name(Direction d) {
    return d == Direction::Request ? "request" : "response";
}

// Decodes the PDU in each allowed direction, wrapping it with the framing rows.
bool describe_framed(codec::Bytes pdu, const DecodeOptions& o, const std::string& what,
                     const std::vector<FieldRow>& head, const std::vector<FieldRow>& tail,
                     std::vector<Decoded>& out, std::string& last_error) {
    bool any = false;
    for (Direction d : directions(o)) {
        Decoded dec;
        dec.rows = head;
        std::string err;
        if (!describe_pdu(pdu, d, dec.rows, err)) {
            last_error = fmt::format("{} as {}: {}", what, direction_name(d), err);
            continue;
        }
        dec.rows.insert(dec.rows.end(), tail.begin(), tail.end());
        dec.title = fmt::format("{} {}", what, direction_name(d));
        out.push_back(std::move(dec));
        any = true;
    }
    return any;
}

bool decode_tcp(codec::Bytes bytes, const DecodeOptions& o, std::vector<Decoded>& out,
                std::string& error) {
    // The splitter lets one input hold several pipelined ADUs.
    codec::MbapSplitter splitter;
    splitter.feed(bytes);
    codec::TcpFrame frame;
    int index = 0;
    for (;;) {
        auto status = splitter.next(frame);
        if (status == codec::MbapSplitter::Status::NeedMore) break;
        if (status == codec::MbapSplitter::Status::Fatal) {
            error = fmt::format("bad MBAP header: {}", codec::error_description(splitter.error()));
            return false;
        }
        ++index;
        const auto& h = frame.header;
        std::vector<FieldRow> head{
            {"Transaction identifier", codec::format_hex(frame.adu.subspan(0, 2)),
             std::to_string(h.transaction_id)},
            {"Protocol identifier", codec::format_hex(frame.adu.subspan(2, 2)),
             h.protocol_id == 0
                 ? "0 (Modbus)"
                 : fmt::format("{} (not Modbus: a server discards it)", h.protocol_id)},
            {"Length", codec::format_hex(frame.adu.subspan(4, 2)),
             fmt::format("{} (unit id + PDU)", h.length)},
            {"Unit identifier", codec::format_hex(frame.adu.subspan(6, 1)),
             std::to_string(h.unit_id)},
        };
        std::string what = fmt::format(
            "Modbus TCP ADU{} ({} bytes)",
            index > 1 || splitter.pending() ? fmt::format(" #{}", index) : "", frame.adu.size());
        if (!describe_framed(frame.pdu, o, what, head, {}, out, error)) return false;
    }
    if (index == 0 || splitter.buffered() != 0) {
        error =
            fmt::format("truncated Modbus TCP frame: {} bytes left over after {} complete frame(s)",
                        splitter.buffered(), index);
        return false;
    }
    return true;
}

bool decode_rtu(codec::Bytes bytes, const DecodeOptions& o, std::vector<Decoded>& out,
                std::string& error) {
    if (bytes.size() < 4) {
        error = fmt::format("RTU frame too short: {} bytes (address, function, CRC need 4)",
                            bytes.size());
        return false;
    }
    std::uint16_t computed = codec::crc16(bytes.first(bytes.size() - 2));
    std::uint16_t carried =
        static_cast<std::uint16_t>(bytes[bytes.size() - 2] | (bytes[bytes.size() - 1] << 8));
    std::string crc_meaning = computed == carried
                                  ? fmt::format("0x{:04X} correct (low byte first)", carried)
                                  : fmt::format("0x{:04X} WRONG: expected {:02X} {:02X}", carried,
                                                computed & 0xFF, computed >> 8);
    std::vector<FieldRow> head{{"Slave address", codec::format_hex(bytes.first(1)),
                                bytes[0] == 0 ? "0 (broadcast)" : std::to_string(bytes[0])}};
    std::vector<FieldRow> tail{{"CRC", codec::format_hex(bytes.last(2)), crc_meaning}};
    auto pdu = bytes.subspan(1, bytes.size() - 3);
    std::string what = fmt::format("Modbus RTU frame ({} bytes, CRC {})", bytes.size(),
                                   computed == carried ? "ok" : "BAD");
    return describe_framed(pdu, o, what, head, tail, out, error);
}

bool decode_ascii(std::string text, const DecodeOptions& o, std::vector<Decoded>& out,
                  std::string& error) {
    // Shells eat the CR LF; accept a frame without it.
    if (text.size() < 2 || text.substr(text.size() - 2) != "\r\n") text += "\r\n";
    std::array<std::uint8_t, codec::limits::kMaxAsciiAdu> buf{};
    codec::AsciiFrame frame;
    auto err = codec::decode_ascii_frame(std::string_view(text), buf, frame);
    if (err != codec::CodecError::Ok) {
        error = fmt::format("bad ASCII frame: {}", codec::error_description(err));
        return false;
    }
    std::vector<FieldRow> head{
        {"Start", ":", "frame start"},
        {"Slave address", codec::format_hex(frame.binary.first(1)), std::to_string(frame.address)}};
    std::vector<FieldRow> tail{{"LRC", codec::format_hex(frame.binary.last(1)), "correct"},
                               {"End", "CR LF", "frame end"}};
    return describe_framed(frame.pdu, o,
                           fmt::format("Modbus ASCII frame ({} characters)", text.size()), head,
                           tail, out, error);
}

Framing guess_framing(codec::Bytes bytes) {
    if (bytes.size() >= 8) {
        auto h = codec::read_mbap_header(bytes.data());
        if (h.protocol_id == 0 && h.length >= 2 && h.length + 6u <= bytes.size())
            return Framing::Tcp;
    }
    if (bytes.size() >= 4) {
        std::uint16_t crc = codec::crc16(bytes.first(bytes.size() - 2));
        if ((crc & 0xFF) == bytes[bytes.size() - 2] && (crc >> 8) == bytes[bytes.size() - 1])
            return Framing::Rtu;
    }
    return Framing::Pdu;
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

    std::vector<Decoded> decoded;
    std::string error;
    bool ok = false;
    if (framing == Framing::Ascii) {
        ok = decode_ascii(text, o, decoded, error);
    } else {
        std::array<std::uint8_t, 4096> buf{};
        auto parsed = codec::parse_hex(text, buf);
        if (!parsed.ok()) {
            fmt::print(stderr, "mbstorm decode: bad hex at character {}: {}\n", parsed.position + 1,
                       parsed.error == codec::CodecError::OddHexLength ? "odd number of hex digits"
                                                                       : "not a hex digit");
            return kExitUsage;
        }
        codec::Bytes bytes(buf.data(), parsed.size);
        if (framing == Framing::Auto) framing = guess_framing(bytes);
        switch (framing) {
            case Framing::Tcp:
                ok = decode_tcp(bytes, o, decoded, error);
                break;
            case Framing::Rtu:
                ok = decode_rtu(bytes, o, decoded, error);
                break;
            default:
                ok = describe_framed(bytes, o, fmt::format("Modbus PDU ({} bytes)", bytes.size()),
                                     {}, {}, decoded, error);
        }
    }
    if (!ok) {
        fmt::print(stderr, "mbstorm decode: {}\n", error);
        return kExitUsage;
    }
    for (std::size_t i = 0; i < decoded.size(); ++i) {
        fmt::print("{}{}:\n{}", i ? "\n" : "", decoded[i].title, render_rows(decoded[i].rows));
    }
    return kExitOk;
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
