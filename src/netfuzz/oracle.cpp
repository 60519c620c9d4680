#include "netfuzz/oracle.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <optional>

#include "codec/exception_code.hpp"
#include "codec/function_code.hpp"
#include "codec/rtu.hpp"
#include "codec/values.hpp"
#include "netfuzz/rules.hpp"

namespace mbstorm::netfuzz {
namespace {

using codec::ExceptionCode;
using codec::load_be16;

constexpr std::array<std::string_view, static_cast<std::size_t>(Oracle::Count)> kOracleNames = {
    "none", "crash", "hang", "unexpected-close", "malformed-response", "spec-deviation"};

std::string exception_text(std::uint8_t code) {
    return fmt::format("exception {:02X} ({})", code,
                       codec::exception_name(static_cast<ExceptionCode>(code)));
}

std::string request_text(const RequestInfo& rq) {
    return fmt::format("{} unit {} tid {:04X}: {}",
                       codec::function_label(rq.pdu.empty() ? 0 : rq.pdu[0]), rq.header.unit_id,
                       rq.header.transaction_id, hex(rq.pdu, 24));
}

Verdict make(Oracle o, std::string rule, const RequestInfo& rq, std::string summary,
             std::string expected, std::string seen) {
    return Verdict{o,
                   std::move(rule),
                   rq.pdu.empty() ? -1 : rq.pdu[0],
                   std::move(summary),
                   std::move(expected),
                   std::move(seen),
                   rq.header.unit_id};
}

// Function codes whose sub-function (or object) support legitimately varies per device, so a
// 01 answer is acceptable for any of their requests.
bool sub_function_varies(std::uint8_t fc) noexcept {
    using codec::RequestShape;
    return codec::request_is(fc, RequestShape::SubFunction) ||
           codec::request_is(fc, RequestShape::MeiTransport) ||
           codec::request_is(fc, RequestShape::FileRecords);
}

constexpr std::uint8_t code_of(ExceptionCode e) noexcept {
    return static_cast<std::uint8_t>(e);
}

}  // namespace

std::string_view oracle_name(Oracle o) noexcept {
    const auto i = static_cast<std::size_t>(o);
    return i < kOracleNames.size() ? kOracleNames[i] : "unknown";
}

bool oracle_from_name(std::string_view name, Oracle& out) noexcept {
    for (std::size_t i = 0; i < kOracleNames.size(); ++i) {
        if (kOracleNames[i] == name) {
            out = static_cast<Oracle>(i);
            return true;
        }
    }
    return false;
}

std::string hex(codec::Bytes bytes, std::size_t max) {
    std::string s;
    const std::size_t n = std::min(bytes.size(), max);
    s.reserve(n * 3 + 4);
    for (std::size_t i = 0; i < n; ++i) {
        if (i) s += ' ';
        s += fmt::format("{:02X}", bytes[i]);
    }
    if (bytes.size() > max) s += " ...";
    return s;
}

std::string_view request_kind(const RequestInfo& info) noexcept {
    if (info.status.error == codec::CodecError::UnsupportedFunction) return kUnknownFunctionCulprit;
    return info.status.ok() ? "valid" : "invalid";
}

std::string culprit_text(MutationClass cls, const RequestInfo* rq) {
    // Every mutation that delivers a frame in pieces meets the same code: the target's
    // reassembly of a started frame.
    if (cls == MutationClass::Split || cls == MutationClass::BurstSplit ||
        cls == MutationClass::PartialHold || cls == MutationClass::Drip)
        return kPartialFrameCulprit;
    // A frame that is not Modbus (protocol id not 0) meets no function's handler.
    if (is_transport_class(cls) || cls == MutationClass::ProtocolId || !rq || rq->pdu.empty())
        return std::string(class_name(cls));
    if (request_kind(*rq) == kUnknownFunctionCulprit) return kUnknownFunctionCulprit;
    // The function code alone: one handler, whether this request was valid or not.
    return function_culprit(rq->pdu[0]);
}

bool pdu_length_mismatch(const RequestInfo& info) noexcept {
    if (info.pdu.empty()) return false;
    if (info.status.error == codec::CodecError::UnsupportedFunction) return true;
    // The length a reader that frames by function code would take: the codec's RTU length
    // rule (the same fields decide it), asked of unit + PDU + two bytes where the CRC would be.
    // The codec's first complaint may be another (a quantity), so its status is not enough.
    std::array<std::uint8_t, 1 + codec::limits::kMaxPdu + 2> head{};
    if (info.pdu.size() > codec::limits::kMaxPdu) return true;
    head[0] = info.header.unit_id;
    std::copy(info.pdu.begin(), info.pdu.end(), head.begin() + 1);
    const std::size_t size = info.pdu.size() + 3;
    const codec::RtuLength len = codec::rtu_request_length(codec::Bytes(head.data(), size));
    switch (len.status) {
        case codec::RtuLength::Status::Known:
            return len.size != size;
        case codec::RtuLength::Status::NeedMore:
            return len.size > size;
        case codec::RtuLength::Status::TooLong:
            return true;
        case codec::RtuLength::Status::Unknown:
            return false;
    }
    return false;
}

Verdict understood_by(const TargetProfile& profile, Verdict v) {
    const bool stream_lost_close =
        v.oracle == Oracle::UnexpectedClose && v.rule.rfind(kStreamLostRule, 0) == 0;
    if (profile.refuses_length_mismatch && stream_lost_close) {
        v.rule = kClosesOnInvalidRequestRule;
        v.summary += " (it closes on such a frame alone, before anything follows it)";
    }
    return v;
}

bool owes_exception(const RequestInfo& info, const TargetProfile& profile) noexcept {
    if (info.pdu.empty()) return false;
    return !info.status.ok() || profile.unsupported[info.pdu[0]];
}

void describe_request(codec::Bytes adu, const TargetProfile& profile, RequestInfo& info) noexcept {
    info.header = codec::read_mbap_header(adu.data());
    info.pdu = adu.subspan(codec::limits::kMbapHeader);
    info.status = codec::decode_request(info.pdu, info.request);
    if (info.header.protocol_id != 0) {
        info.expect = Expect::MustBeSilent;
    } else if (info.header.unit_id != profile.unit || info.pdu.empty()) {
        // Other unit ids may be gateway targets that do not answer; an empty PDU has nothing
        // to answer to.
        info.expect = Expect::MayBeSilent;
    } else {
        info.expect = Expect::Answer;
    }
}

// A normal answer to a read covering an address the device refused alone (profile.unmapped).
Verdict check_unmapped(const RequestInfo& rq, const TargetProfile& profile) {
    const codec::Request& q = rq.request;
    const auto table = codec::function_table(q.function);
    if (!table || rq.status.error != codec::CodecError::Ok) return {};
    const bool plain_read = codec::request_is(q.function, codec::RequestShape::AddressQuantity);
    const bool read_write = codec::request_is(q.function, codec::RequestShape::ReadWriteRegisters);
    if (!plain_read && !read_write) return {};
    const auto& unmapped = profile.unmapped[static_cast<std::size_t>(*table)];
    for (const std::uint16_t a : unmapped) {
        if (a < q.address || std::uint32_t{a} >= std::uint32_t{q.address} + q.quantity) continue;
        return make(Oracle::SpecDeviation, unmapped_address_rule(codec::table_name(*table)), rq,
                    fmt::format("{}: a read over address {} answered normally, where a read of "
                                "that address alone gets exception 02",
                                codec::function_label(q.function), a),
                    "exception 02 (ILLEGAL DATA ADDRESS): the range holds an address the device "
                    "does not have",
                    "a normal response");
    }
    return {};
}

namespace {
// A request with bytes past what its function code needs, judged as the request without them
// (v1.1b3's request flows check quantities and byte counts, never the PDU's length beyond
// them, so a server may ignore the rest: FC 0C with one trailing byte answered normally is no
// fault). Its status: the shortest prefix that is not short of bytes.
RequestInfo without_trailing_bytes(const RequestInfo& rq) {
    RequestInfo prefix = rq;
    for (std::size_t n = rq.pdu.size() - 1; n > 0; --n) {
        prefix.pdu = rq.pdu.first(n);
        prefix.request = codec::Request{};
        prefix.status = codec::decode_request(prefix.pdu, prefix.request);
        if (prefix.status.error != codec::CodecError::TrailingBytes) break;
    }
    return prefix;
}
}  // namespace

namespace {

// What every answer is judged with: the request, the answer's PDU and its text.
struct Answer {
    const RequestInfo& rq;
    const TargetProfile& profile;
    codec::MbapHeader header;
    codec::Bytes pdu;
    std::string seen;
    std::uint8_t fc;
    ExceptionCode owed;
    // A sub-function (FC 08) or MEI type (FC 2B) the codec does not know: 01 is owed, and a
    // server that answers anything else has one missing check, whatever it answers instead.
    bool unknown_sub_function;
    std::string expected_text;
};

// An answer to what must be discarded, or one whose header or function is not the request's.
Verdict judge_header(const Answer& a) {
    const RequestInfo& rq = a.rq;
    if (rq.expect == Expect::MustBeSilent && !rq.discard.empty()) {
        return make(Oracle::SpecDeviation, answers_discarded_rule(rq.discard), rq,
                    fmt::format("answered a frame it must discard ({})", rq.discard),
                    "no answer: the frame is discarded", a.seen);
    }
    if (rq.expect == Expect::MustBeSilent) {
        return make(Oracle::SpecDeviation, kAnswersNonzeroProtocolIdRule, rq,
                    fmt::format("answered a frame with protocol id {:04X}", rq.header.protocol_id),
                    "no answer: frames with protocol id != 0 are discarded", a.seen);
    }
    if (a.header.protocol_id != 0) {
        return make(Oracle::MalformedResponse, kResponseProtocolIdRule, rq,
                    fmt::format("response carries protocol id {:04X}", a.header.protocol_id),
                    "protocol id 0000", a.seen);
    }
    if (a.header.unit_id != rq.header.unit_id) {
        return make(Oracle::MalformedResponse, kResponseUnitIdRule, rq,
                    fmt::format("response unit id {} for a request to unit {}", a.header.unit_id,
                                rq.header.unit_id),
                    fmt::format("unit id {}", rq.header.unit_id), a.seen);
    }
    if (a.pdu.empty() || (a.pdu[0] & 0x7F) != (a.fc & 0x7F)) {
        return make(Oracle::MalformedResponse, kResponseFunctionRule, rq,
                    fmt::format("response function 0x{:02X} for request {}",
                                a.pdu.empty() ? 0 : a.pdu[0], codec::function_label(a.fc)),
                    fmt::format("function 0x{:02X} or 0x{:02X}", a.fc & 0x7F,
                                (a.fc & 0x7F) | codec::kExceptionBit),
                    a.seen);
    }
    return {};
}

// Whether exception `code` is a right answer to the request.
bool exception_allowed(const Answer& a, std::uint8_t code) {
    using E = ExceptionCode;
    const bool foreign_unit = a.rq.header.unit_id != a.profile.unit;
    if (code == code_of(E::ServerDeviceBusy) ||
        (foreign_unit && (code == code_of(E::GatewayPathUnavailable) ||
                          code == code_of(E::GatewayTargetFailedToRespond))))
        return true;
    if (a.owed != E::None)
        return code == code_of(a.owed) || a.profile.unsupported[a.fc] ||
               (code == code_of(E::IllegalFunction) && sub_function_varies(a.fc)) ||
               a.profile.extended[a.fc];
    // A valid request may meet an address the device lacks (02), a device failure (04/05) or
    // an unsupported function (01). 03 is only a deviation for the plain reads (01-04), where
    // a valid quantity leaves nothing to object to.
    return code == code_of(E::IllegalFunction) || code == code_of(E::IllegalDataAddress) ||
           code == code_of(E::ServerDeviceFailure) || code == code_of(E::Acknowledge) ||
           (code == code_of(E::IllegalDataValue) &&
            !codec::request_is(a.fc, codec::RequestShape::AddressQuantity));
}

Verdict judge_exception(const Answer& a) {
    if (a.pdu.size() != 2) {
        return make(Oracle::MalformedResponse, kExceptionResponseLengthRule, a.rq,
                    fmt::format("exception response of {} bytes (MBAP length {})", a.pdu.size(),
                                a.header.length),
                    "the function with its exception bit and one exception code byte", a.seen);
    }
    const std::uint8_t code = a.pdu[1];
    if (exception_allowed(a, code)) return {};
    const bool none_owed = a.owed == ExceptionCode::None;
    return make(
        Oracle::SpecDeviation,
        // The codec's reason is left out: one wrong check order shows under every
        // reason that owes the same exception. An unknown sub-function is one missing
        // check however it is answered (see kSubFunctionNot01Rule).
        a.unknown_sub_function ? std::string(kSubFunctionNot01Rule)
        : none_owed            ? exception_to_valid_request_rule(code)
                               : exception_where_owed_rule(code, static_cast<std::uint8_t>(a.owed)),
        a.rq,
        fmt::format("{}: {} where {} is owed", codec::function_label(a.fc), exception_text(code),
                    none_owed ? std::string("a normal response")
                              : exception_text(static_cast<std::uint8_t>(a.owed))),
        a.expected_text, a.seen);
}

// A normal answer's echo against the request, by the function's response shape.
std::string_view echo_fault(codec::ResponseShape shape, const codec::Response& r,
                            const codec::Request& q) {
    using codec::ResponseShape;
    switch (shape) {
        case ResponseShape::EchoValue:
            return r.address != q.address || r.value != q.value ? kEchoDiffersRule : "";
        case ResponseShape::EchoQuantity:
            return r.address != q.address || r.quantity != q.quantity ? kEchoDiffersRule : "";
        case ResponseShape::EchoMask:
            return r.address != q.address || r.and_mask != q.and_mask || r.or_mask != q.or_mask
                       ? kEchoDiffersRule
                       : "";
        case ResponseShape::EchoSubFunction:
            if (r.sub_function != q.sub_function) return kSubFunctionNotEchoedRule;
            if (q.sub_function == 0x0000 &&
                !std::equal(r.payload.begin(), r.payload.end(), q.payload.begin(), q.payload.end()))
                return kQueryDataNotEchoedRule;
            return "";
        case ResponseShape::MeiObjects:
            return r.mei_type != q.mei_type ? kMeiTypeNotEchoedRule : "";
        case ResponseShape::Bits:
        case ResponseShape::Registers:
        case ResponseShape::ExceptionStatus:
        case ResponseShape::EventCounter:
        case ResponseShape::EventLog:
        case ResponseShape::ServerId:
        case ResponseShape::FileRecords:
        case ResponseShape::FifoValues:
            return "";  // their data sizes are checked apart
    }
    return "";
}

std::string_view echo_fault_text(std::string_view rule) {
    if (rule == kSubFunctionNotEchoedRule) return "sub-function not echoed";
    if (rule == kQueryDataNotEchoedRule) return "return-query-data did not echo the data";
    if (rule == kMeiTypeNotEchoedRule) return "MEI type not echoed";
    return "echo differs from the request";
}

Verdict judge_normal_answer(const Answer& a) {
    const RequestInfo& rq = a.rq;
    if (a.owed != ExceptionCode::None && !a.profile.extended[a.fc]) {
        return make(Oracle::SpecDeviation,
                    // One finding per missing check: the handler of this function code (its own
                    // code) skips the check that owes this exception, whichever field failed it
                    // (v1.1b3 gives FC 0F's quantity and byte count one check: pymodbus ignoring FC
                    // 0F's quantity showed as two findings, one per field).
                    a.unknown_sub_function
                        ? std::string(kSubFunctionNot01Rule)
                        : invalid_answered_normally_rule(static_cast<std::uint8_t>(a.owed), a.fc),
                    rq,
                    fmt::format("{}: invalid request answered normally ({} owed: {})",
                                codec::function_label(a.fc),
                                exception_text(static_cast<std::uint8_t>(a.owed)),
                                codec::error_name(rq.status.error)),
                    a.expected_text, a.seen);
    }
    if (a.profile.extended[a.fc]) return {};
    codec::Response r;
    if (const auto err = codec::decode_response(a.pdu, r); err != codec::CodecError::Ok) {
        return make(Oracle::MalformedResponse, undecodable_response_rule(codec::error_name(err)),
                    rq,
                    fmt::format("{}: response does not decode: {}", codec::function_label(a.fc),
                                codec::error_description(err)),
                    a.expected_text, a.seen);
    }
    auto mismatch = [&](std::string_view rule, std::string what) {
        return make(Oracle::MalformedResponse, std::string(rule), rq,
                    fmt::format("{}: {}", codec::function_label(a.fc), what), a.expected_text,
                    a.seen);
    };
    if (Verdict v = check_unmapped(rq, a.profile)) return v;
    const int want = codec::expected_read_byte_count(rq.request);
    if (want >= 0 && static_cast<int>(r.payload.size()) != want)
        return mismatch(kReadDataSizeRule, fmt::format("{} data bytes for a request that needs {}",
                                                       r.payload.size(), want));
    const codec::FunctionInfo* info = codec::function_info(a.fc);
    if (!info) return {};
    const std::string_view fault = echo_fault(info->response, r, rq.request);
    if (!fault.empty()) return mismatch(fault, std::string(echo_fault_text(fault)));
    return {};
}

}  // namespace

Verdict judge_response(const RequestInfo& rq, codec::Bytes rsp, const TargetProfile& profile) {
    if (rq.status.error == codec::CodecError::TrailingBytes && rq.pdu.size() > 1) {
        // 03 for them is right too (the codec's own reading).
        const codec::Bytes answer = rsp.subspan(codec::limits::kMbapHeader);
        const bool refused_03 = answer.size() == 2 &&
                                answer[0] == (rq.pdu[0] | codec::kExceptionBit) &&
                                answer[1] == code_of(ExceptionCode::IllegalDataValue);
        if (refused_03) return {};
        return judge_response(without_trailing_bytes(rq), rsp, profile);
    }
    const auto owed = rq.status.exception;
    const Answer a{rq,
                   profile,
                   codec::read_mbap_header(rsp.data()),
                   rsp.subspan(codec::limits::kMbapHeader),
                   hex(rsp),
                   static_cast<std::uint8_t>(rq.pdu.empty() ? 0 : rq.pdu[0]),
                   owed,
                   rq.status.error == codec::CodecError::UnsupportedSubFunction,
                   owed != ExceptionCode::None
                       ? exception_text(static_cast<std::uint8_t>(owed))
                       : fmt::format("a normal response to {}", request_text(rq))};
    if (Verdict v = judge_header(a)) return v;
    return (a.pdu[0] & codec::kExceptionBit) ? judge_exception(a) : judge_normal_answer(a);
}

void relocate_writes(std::uint8_t* adu, std::size_t size, const StateRange& state) noexcept {
    if (size < codec::limits::kMbapHeader + 5 || state.whole_map()) return;
    std::uint8_t* p = adu + codec::limits::kMbapHeader;
    const std::uint8_t fc = p[0];
    using codec::RequestShape;
    // Writes without an address of the tables (file records, diagnostics) are left alone.
    if (!codec::is_write_function(fc) || codec::request_is(fc, RequestShape::FileRecords) ||
        codec::request_is(fc, RequestShape::SubFunction))
        return;
    // Address field: read/write requests write at offset 5, the others at offset 1.
    const bool read_write = codec::request_is(fc, RequestShape::ReadWriteRegisters);
    const std::size_t at = read_write ? 5 : 1;
    if (codec::limits::kMbapHeader + at + 2 > size) return;
    const std::uint16_t a = load_be16(p + at);
    std::uint32_t qty = 1;
    if ((codec::request_is(fc, RequestShape::MultipleCoils) ||
         codec::request_is(fc, RequestShape::MultipleRegisters)) &&
        size >= codec::limits::kMbapHeader + 5)
        qty = load_be16(p + 3);
    if (read_write && size >= codec::limits::kMbapHeader + 9) qty = load_be16(p + 7);
    const std::uint32_t end = std::uint32_t{a} + std::max<std::uint32_t>(qty, 1);
    if (end > state.base && a < state.base + state.span) {
        // Move it out of the range (keeps the value's low bits, so limits near 0 survive).
        const std::uint32_t below = state.base ? a % state.base : 0;
        const std::uint32_t moved =
            state.base >= std::max<std::uint32_t>(qty, 1)
                ? std::min(below, state.base - std::max<std::uint32_t>(qty, 1))
                : state.base + state.span;
        codec::store_be16(p + at, static_cast<std::uint16_t>(moved));
    }
}

namespace {

struct WriteRecord {
    bool coils = false;
    std::uint16_t address = 0;
    std::vector<std::optional<std::uint16_t>> values;  // nullopt: unknown
    std::int64_t sent = 0, acked = 0;                  // acked 0: no normal answer
    const RequestInfo* self = nullptr;
    std::uint8_t conn = 0;
    bool mask = false;  // FC16: its value follows from the one before it
};

// The values a write request stores (nullopt where they depend on unknown state).
std::optional<WriteRecord> write_of(const RequestInfo& rq) {
    if (rq.status.error != codec::CodecError::Ok || rq.header.protocol_id != 0) return {};
    const codec::Request& q = rq.request;
    WriteRecord w;
    w.self = &rq;
    const codec::FunctionInfo* info = codec::function_info(q.function);
    if (!info) return {};
    switch (info->request) {
        case codec::RequestShape::SingleCoil:
            w.coils = true;
            w.address = q.address;
            w.values = {static_cast<std::uint16_t>(q.value == 0xFF00)};
            break;
        case codec::RequestShape::SingleRegister:
            w.address = q.address;
            w.values = {q.value};
            break;
        case codec::RequestShape::MultipleCoils:
            w.coils = true;
            w.address = q.address;
            for (std::uint16_t i = 0; i < q.quantity; ++i)
                w.values.push_back(static_cast<std::uint16_t>((q.payload[i / 8] >> (i % 8)) & 1));
            break;
        case codec::RequestShape::MultipleRegisters:
            w.address = q.address;
            for (std::uint16_t i = 0; i < q.quantity; ++i)
                w.values.push_back(load_be16(q.payload.data() + 2 * i));
            break;
        case codec::RequestShape::ReadWriteRegisters:
            w.address = q.write_address;
            for (std::uint16_t i = 0; i < q.write_quantity; ++i)
                w.values.push_back(load_be16(q.payload.data() + 2 * i));
            break;
        case codec::RequestShape::MaskWrite:
            w.address = q.address;
            w.values = {std::nullopt};  // depends on the old value: see resolve_masks
            w.mask = true;
            break;
        case codec::RequestShape::FunctionOnly:
        case codec::RequestShape::AddressQuantity:
        case codec::RequestShape::SubFunction:  // restarts and clears counters, not data
        case codec::RequestShape::FileRecords:  // file records are not in the shadow
        case codec::RequestShape::FifoPointer:
        case codec::RequestShape::MeiTransport:
            return {};
    }
    return w;
}

// A mask write stores (old AND and_mask) OR (or_mask AND NOT and_mask) (v1.1b3, 6.16): its
// value is known when an acknowledged write before it left a known value at its address.
void resolve_masks(std::vector<WriteRecord>& writes) {
    for (WriteRecord& m : writes) {
        if (!m.mask || !m.acked) continue;
        const WriteRecord* latest = nullptr;
        for (const WriteRecord& w : writes) {
            // Before it: acknowledged before it went out, or sent before it on its connection
            // (a server takes one connection's requests in order).
            const bool before = w.acked <= m.sent || (w.conn == m.conn && w.sent < m.sent);
            if (&w == &m || w.coils || !w.acked || !before) continue;
            if (m.address < w.address || m.address >= w.address + w.values.size()) continue;
            if (!latest || w.sent > latest->sent) latest = &w;
        }
        if (!latest) continue;
        const auto& old = latest->values[m.address - latest->address];
        if (!old) continue;
        const codec::Request& q = m.self->request;
        m.values[0] = static_cast<std::uint16_t>((*old & q.and_mask) | (q.or_mask & ~q.and_mask));
    }
}

// The write whose value a read answered at `address` must show: the latest acknowledged before
// the read went out (or the read's own, for FC17), with `index` its value's. Null when there
// is none, or when a write was in flight while the read was (either order is right).
const WriteRecord* latest_write(const Shadow::Event& e, const std::vector<WriteRecord>& writes,
                                bool coils, std::uint32_t address, std::size_t& index) {
    const RequestInfo& rq = *e.request;
    const WriteRecord* latest = nullptr;
    bool ambiguous = false;
    for (const WriteRecord& w : writes) {
        if (w.coils != coils || address < w.address || address >= w.address + w.values.size())
            continue;
        if (w.self == &rq) {  // FC17 writes before it reads
            latest = &w;
            index = address - w.address;
            continue;
        }
        const bool before = w.acked != 0 && w.acked <= e.sent_ns;
        const bool overlaps = w.sent < e.answered_ns && !before;
        if (overlaps) ambiguous = true;
        // The later of two: acknowledged later, or in the same reply sent later, or sent in
        // the same send and later in the stream (the events are in stream order).
        const bool later = latest && (w.acked > latest->acked ||
                                      (w.acked == latest->acked && w.sent >= latest->sent));
        if (before && (!latest || (latest->self != &rq && later))) {
            latest = &w;
            index = address - w.address;
        }
    }
    return ambiguous ? nullptr : latest;
}

// One read's values against the latest acknowledged write of each address it covers, among
// writes on its own connection or on the others.
Verdict check_read(const Shadow::Event& e, const std::vector<WriteRecord>& writes,
                   const StateRange& state, bool other_connection) {
    const RequestInfo& rq = *e.request;
    if (rq.status.error != codec::CodecError::Ok || e.answered_ns == 0 ||
        e.response_pdu.size() < 2 || (e.response_pdu[0] & codec::kExceptionBit))
        return {};
    // Readers of the tables stateful cases write: coils and holding registers.
    const std::uint8_t fc = rq.request.function;
    const auto table = codec::function_table(fc);
    const bool coils = table == codec::Table::Coils;
    if (!coils && table != codec::Table::HoldingRegisters) return {};
    if (!codec::response_is(fc, codec::ResponseShape::Bits) &&
        !codec::response_is(fc, codec::ResponseShape::Registers))
        return {};
    const std::uint16_t start = rq.request.address;
    const codec::Bytes data = e.response_pdu.subspan(2);
    for (std::uint32_t i = 0; i < rq.request.quantity; ++i) {
        const std::uint32_t a = start + i;
        if (!state.contains(a)) continue;
        std::size_t latest_index = 0;
        const WriteRecord* latest = latest_write(e, writes, coils, a, latest_index);
        if (!latest || !latest->values[latest_index]) continue;
        if ((latest->conn != e.conn) != other_connection) continue;
        const std::uint16_t want = *latest->values[latest_index];
        std::uint16_t got;
        if (coils) {
            if (i / 8 >= data.size()) continue;
            got = (data[i / 8] >> (i % 8)) & 1;
        } else {
            if (2 * i + 1 >= data.size()) continue;
            got = load_be16(data.data() + 2 * i);
        }
        if (got == want) continue;
        const std::uint8_t writer = latest->self->request.function;
        return make(
            Oracle::SpecDeviation,
            read_after_write_rule(other_connection, coils ? "coils" : "holding-registers", writer),
            *latest->self,
            fmt::format("read-after-write mismatch{}: {} {:04X} wrote {:04X}, read "
                        "back {:04X}",
                        other_connection ? " on another connection" : "",
                        coils ? "coil" : "holding register", a, want, got),
            fmt::format("{:04X} (written by {}, acknowledged)", want,
                        codec::function_label(writer)),
            fmt::format("{:04X} in {}", got, hex(e.response_pdu)));
    }
    return {};
}

}  // namespace

Verdict Shadow::check(std::vector<Event>& events, const StateRange& state) {
    std::vector<WriteRecord> writes;
    for (const Event& e : events) {
        auto w = write_of(*e.request);
        if (!w) continue;
        const bool normal = e.answered_ns != 0 && !e.response_pdu.empty() &&
                            !(e.response_pdu[0] & codec::kExceptionBit);
        w->sent = e.sent_ns;
        w->acked = normal ? e.answered_ns : 0;
        w->conn = e.conn;
        if (!normal)
            for (auto& v : w->values) v.reset();
        writes.push_back(std::move(*w));
    }
    if (writes.empty()) return {};
    resolve_masks(writes);
    for (const bool other_connection : {false, true})
        for (const Event& e : events)
            if (Verdict v = check_read(e, writes, state, other_connection)) return v;
    return {};
}

}  // namespace mbstorm::netfuzz
