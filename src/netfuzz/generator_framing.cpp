// The generator's cases in RTU or ASCII framing (Generator::adapt_to_framing): reframed from
// the MBAP cases it makes, and the framing's own transport mutations (bad CRC/LRC, and on a
// serial line broken silences, frames without a silence, noise before a frame).
#include <algorithm>

#include "codec/limits.hpp"
#include "codec/mbap.hpp"
#include "netfuzz/generator.hpp"
#include "netfuzz/wire.hpp"

namespace mbstorm::netfuzz {
namespace {

namespace lim = codec::limits;

// Classes about MBAP fields or about many frames in flight: nothing to reframe.
bool mbap_only(MutationClass c) noexcept {
    switch (c) {
        case MutationClass::TransactionId:
        case MutationClass::ProtocolId:
        case MutationClass::MbapLength:
        case MutationClass::TrailingBytes:
        case MutationClass::Coalesced:
        case MutationClass::BurstSplit:
        case MutationClass::HalfCloseAnswered:
            return true;
        default:
            return false;
    }
}

bool one_frame_per_send(const Case& c) {
    for (const Step& s : c.steps) {
        if (s.op != Op::Send) continue;
        if (s.bytes.size() <= lim::kMbapHeader ||
            codec::announced_adu_size(s.bytes.data()) != s.bytes.size())
            return false;
    }
    return true;
}

// Where MBAP byte offset `b` of a frame falls in the same frame in RTU or ASCII framing (the
// header has no counterpart but the unit id).
std::size_t wire_offset(std::size_t b, codec::Framing framing) noexcept {
    if (b <= lim::kMbapHeader - 1) return 0;
    const std::size_t k = b - (lim::kMbapHeader - 1);  // unit and PDU bytes so far
    return framing == codec::Framing::Rtu ? k : 1 + 2 * k;
}

constexpr char kHex[] = "0123456789ABCDEF";

// The case's pieces of one MBAP frame (`whole`, all its Send bytes, maybe short of the frame)
// cut at the same places of the frame reframed; a piece that was all MBAP header is dropped.
void recut_pieces(Case& out, const std::vector<std::uint8_t>& whole, codec::Framing framing) {
    const std::size_t full = codec::announced_adu_size(whole.data());
    std::vector<std::uint8_t> wire;
    std::size_t wire_end;
    if (whole.size() == full) {
        wire = reframe(whole, framing);
        wire_end = wire.size();
    } else {  // a partial frame: the reframed bytes up to where the MBAP bytes stopped
        std::vector<std::uint8_t> head(whole);
        head.resize(std::max(whole.size(), lim::kMbapHeader));
        wire = reframe(head, framing);
        wire_end = std::clamp<std::size_t>(wire_offset(whole.size(), framing), 1, wire.size());
    }
    std::vector<Step> steps;
    std::size_t mbap_at = 0, wire_at = 0;
    for (Step& s : out.steps) {
        if (s.op != Op::Send) {
            steps.push_back(std::move(s));
            continue;
        }
        mbap_at += s.bytes.size();
        const std::size_t to =
            mbap_at == whole.size() ? wire_end : std::min(wire_offset(mbap_at, framing), wire_end);
        if (to <= wire_at) continue;  // this piece was all MBAP header
        s.bytes.assign(wire.begin() + static_cast<std::ptrdiff_t>(wire_at),
                       wire.begin() + static_cast<std::ptrdiff_t>(to));
        wire_at = to;
        steps.push_back(std::move(s));
    }
    out.steps = std::move(steps);
}

}  // namespace

void Generator::adapt_to_framing(Case& out) {
    if (options_.framing == codec::Framing::Mbap) return;
    out.pipelinable = false;  // no transaction ids: one request in flight, so cases run alone
    const bool serial = options_.serial_line;
    bool more_links = false;  // floods and concurrent probes need links a line does not have
    bool conn0_only = true;
    for (const Step& s : out.steps) {
        more_links = more_links || s.op == Op::Flood || s.op == Op::SideProbe;
        conn0_only = conn0_only && (s.op != Op::Send || s.conn == 0);
    }
    if (mbap_only(out.cls) || (serial && more_links)) {
        framing_transport(out);
        return;
    }
    if (one_frame_per_send(out)) {
        for (Step& s : out.steps) {
            if (s.op != Op::Send) continue;
            s.bytes = reframe(s.bytes, options_.framing);
            if (serial) s.conn = 0;  // one line: a second connection is the same line
        }
        return;
    }
    // One frame delivered in pieces (split, drip, a held or half-closed partial frame): the
    // same cuts on the reframed bytes. Over TCP only: on a line any gap breaks a frame.
    std::vector<std::uint8_t> whole;
    for (const Step& s : out.steps)
        if (s.op == Op::Send) whole.insert(whole.end(), s.bytes.begin(), s.bytes.end());
    if (serial || !conn0_only || whole.size() < lim::kMbapHeader - 1 ||
        codec::announced_adu_size(whole.data()) < whole.size()) {
        framing_transport(out);
        return;
    }
    recut_pieces(out, whole, options_.framing);
}

void Generator::framing_transport(Case& out) {
    out.steps.clear();
    out.pipelinable = false;
    const auto& pdu = valid_seed();
    out.function = pdu[0];
    auto framed = [&](const std::vector<std::uint8_t>& p) {
        std::vector<std::uint8_t> f = frame(p, options_.unit);
        relocate_writes(f.data(), f.size(), options_.state);
        return reframe(f, options_.framing);
    };
    std::vector<std::uint8_t> f = framed(pdu);
    const bool rtu = options_.framing == codec::Framing::Rtu;
    // Over TCP a stream has no silences to break: only the checksum is the framing's own.
    const std::uint32_t roll = options_.serial_line ? rng_.below(4) : 0;
    if (roll == 0 || (roll == 1 && !rtu)) {
        out.cls = MutationClass::BadChecksum;
        if (rtu) {
            f[f.size() - 1 - rng_.below(2)] ^= static_cast<std::uint8_t>(1u << rng_.below(8));
        } else {  // the LRC's last hex digit, changed to another
            std::uint8_t& digit = f[f.size() - 3];
            const auto at = static_cast<std::size_t>(std::find(kHex, kHex + 16, digit) - kHex);
            digit = static_cast<std::uint8_t>(kHex[(at + 1 + rng_.below(15)) % 16]);
        }
        out.steps.push_back(Step{Op::Send, 0, 0, 0, std::move(f)});
    } else if (roll == 1) {  // RTU on a line: a gap of twice t1.5 inside the frame
        out.cls = MutationClass::BrokenSilence;
        const std::uint32_t at = 1 + rng_.below(static_cast<std::uint32_t>(f.size() - 1));
        out.steps.push_back(Step{Op::Send, 0, 0, 0, {f.begin(), f.begin() + at}});
        out.steps.push_back(
            Step{Op::Send, 0, 2 * options_.intercharacter_us, 0, {f.begin() + at, f.end()}});
    } else if (roll == 2) {
        out.cls = MutationClass::NoSilence;
        const std::vector<std::uint8_t> second = framed(valid_seed());
        f.insert(f.end(), second.begin(), second.end());
        out.steps.push_back(Step{Op::Send, 0, 0, 0, std::move(f)});
    } else {
        out.cls = MutationClass::Noise;
        std::vector<std::uint8_t> noise(1 + rng_.below(8));
        for (auto& b : noise) {
            b = rng_.byte();
            if (!rtu && (b == ':' || b == '\n')) b = '?';
        }
        if (rtu) {
            // Noise, a silence, then the frame: the noise is a (broken) frame of its own. The
            // silence is well over t3.5 (the link keeps t3.5 itself), so that a slave reading
            // a pseudo-terminal, whose timing jitters, still sees it.
            out.steps.push_back(Step{Op::Send, 0, 0, 0, std::move(noise)});
            out.steps.push_back(
                Step{Op::Send, 0, 4 * options_.intercharacter_us + 2000, 0, std::move(f)});
        } else {  // ASCII readers skip to the next ':'
            noise.insert(noise.end(), f.begin(), f.end());
            out.steps.push_back(Step{Op::Send, 0, 0, 0, std::move(noise)});
        }
    }
}

}  // namespace mbstorm::netfuzz
