#include "netfuzz/discovery.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstring>
#include <thread>

#include "codec/exception_code.hpp"
#include "codec/function_code.hpp"
#include "codec/limits.hpp"
#include "codec/mbap.hpp"
#include "codec/pdu.hpp"
#include "net/clock.hpp"
#include "netfuzz/ask.hpp"
#include "netfuzz/executor.hpp"
#include "netfuzz/finding.hpp"

namespace mbstorm::netfuzz {
namespace {

using Pdu = std::vector<std::uint8_t>;

// How much longer than --restart-wait a --restart-cmd that has not returned may take.
constexpr std::int64_t kRestartCommandGraceNs = 60 * net::kNsPerSec;

// Why discovery found no request to probe with: silence, or answers it cannot use (a device
// answering everything with 04 does answer: say what it said).
std::string no_usable_answer(std::uint8_t unit, const std::vector<Pdu>& probes,
                             const std::vector<Pdu>& answers) {
    std::string said;
    bool any = false;
    for (std::size_t i = 0; i < probes.size(); ++i) {
        const Pdu& a = answers[i];
        any = any || !a.empty();
        std::string what =
            a.empty() ? std::string("no answer")
            : a.size() == 2 && a[0] == (probes[i][0] | codec::kExceptionBit)
                ? fmt::format("exception {:02X} ({})", a[1],
                              codec::exception_name(static_cast<codec::ExceptionCode>(a[1])))
                : fmt::format("{} ({})",
                              a.size() == 1 ? "1 byte" : fmt::format("{} bytes", a.size()),
                              hex(a, 8));
        said += fmt::format("{}0x{:02X}: {}", said.empty() ? "" : ", ", probes[i][0], what);
    }
    if (!any) return fmt::format("the target does not answer unit {} ({})", unit, said);
    return fmt::format(
        "the target answers unit {} but no read with a normal response or exception 02, so "
        "there is nothing to probe it with ({})",
        unit, said);
}

// The first read the target answers normally, else the first it answers with 02 (a device
// whose map does not start at 0 answers every canonical read so: 02, its address check, will do
// until the model gives a read inside the map). A Network error: no connection; InvalidInput:
// the target answers, but none of the probes usably (the user picked the wrong unit or device).
Error choose_probe(Connector& target, int timeout_ms, TargetProfile& profile) {
    using codec::FunctionCode;
    std::vector<Pdu> probes;
    for (FunctionCode fc : {FunctionCode::ReadHoldingRegisters, FunctionCode::ReadInputRegisters,
                            FunctionCode::ReadCoils, FunctionCode::ReadDiscreteInputs,
                            FunctionCode::ReportServerId, FunctionCode::Diagnostics})
        probes.push_back(canonical_request(*codec::function_info(codec::to_byte(fc))));
    std::vector<Pdu> frames;
    for (std::size_t i = 0; i < probes.size(); ++i)
        frames.push_back(
            frame_pdu(probes[i], static_cast<std::uint16_t>(i), profile.unit, profile.framing));
    bool connected = false;
    const std::vector<Pdu> answers = ask_pipelined(target, frames, timeout_ms, connected);
    if (!connected) {
        // Once more, for the reason (refused, unreachable, timed out): the user has to act on it.
        int why = 0;
        return Error(ErrorCode::Network, target.open(timeout_ms, why)
                                             ? std::string("cannot connect to the target")
                                             : fmt::format("cannot connect to the target: {}",
                                                           why ? std::strerror(why) : "timed out"));
    }
    for (std::size_t i = 0; i < probes.size() && profile.probe_pdu.empty(); ++i)
        if (!answers[i].empty() && answers[i][0] == probes[i][0]) profile.probe_pdu = probes[i];
    for (std::size_t i = 0; i < probes.size() && profile.probe_pdu.empty(); ++i)
        if (answers[i].size() == 2 && answers[i][0] == (probes[i][0] | codec::kExceptionBit) &&
            answers[i][1] == static_cast<std::uint8_t>(codec::ExceptionCode::IllegalDataAddress))
            profile.probe_pdu = probes[i];
    if (profile.probe_pdu.empty())
        return Error(ErrorCode::InvalidInput, no_usable_answer(profile.unit, probes, answers));
    return Error::none();
}

// Requests pipelined behind the exception when asking whether the target drops them: all of
// them unanswered is a target that drops what follows an exception; one or two unanswered is a
// target that drops requests now and then (a lossy link) and one drop happened to land there.
constexpr std::size_t kProbesBehindException = 3;

// Does the target drop what is pipelined behind a request it answers with an exception (as
// libmodbus does: it sleeps, then flushes its input)? Then everything after discovery goes one
// request at a time.
bool drops_after_exception(Connector& target, const TargetProfile& profile, int timeout_ms) {
    const std::uint8_t undefined_function = 0x41;
    std::vector<Pdu> frames{frame_pdu(Pdu{undefined_function}, 0, profile.unit)};
    for (std::size_t i = 1; i <= kProbesBehindException; ++i)
        frames.push_back(frame_pdu(profile.probe_pdu, static_cast<std::uint16_t>(i), profile.unit));
    bool connected = false;
    const std::vector<Pdu> answers = ask_pipelined(target, frames, timeout_ms, connected);
    const bool exception = answers[0].size() == 2 && (answers[0][0] & codec::kExceptionBit);
    return exception &&
           std::all_of(answers.begin() + 1, answers.end(), [](const Pdu& a) { return a.empty(); });
}

// Every canonical request, and (where pipelining costs nothing) every undefined function
// code, each asked once; the probe last, pipelined behind them, tells whether the stream went
// on. RTU and ASCII, or a target that drops what follows an exception: one at a time, the
// undefined codes assumed unsupported (each would cost a timeout or the target's pause).
std::vector<Pdu> ask_every_function(Connector& target, const TargetProfile& profile, int timeout_ms,
                                    std::vector<Pdu>& pdus) {
    const bool framed = profile.framing != codec::Framing::Mbap;
    pdus = canonical_requests();
    if (!framed && !profile.drops_after_exception)
        for (unsigned fc = 0; fc < 256; ++fc)
            if (!codec::is_supported_function(static_cast<std::uint8_t>(fc)))
                pdus.push_back(Pdu{static_cast<std::uint8_t>(fc)});
    pdus.push_back(profile.probe_pdu);
    bool connected = false;
    if (framed || !profile.drops_after_exception) {
        std::vector<Pdu> frames;
        for (std::size_t i = 0; i < pdus.size(); ++i)
            frames.push_back(frame_pdu(pdus[i], framed ? 0 : static_cast<std::uint16_t>(i),
                                       profile.unit, profile.framing));
        return ask_pipelined(target, frames, timeout_ms, connected);
    }
    std::vector<Pdu> answers(pdus.size());
    for (std::size_t i = 0; i + 1 < pdus.size(); ++i)
        answers[i] =
            ask_pipelined(target, {frame_pdu(pdus[i], 0, profile.unit)}, timeout_ms, connected)
                .front();
    return answers;
}

// What the answers to every function say: unsupported (01), silent, or a vendor extension.
void learn_functions(const std::vector<Pdu>& pdus, const std::vector<Pdu>& answers,
                     TargetProfile& profile) {
    // Silence counts only where the stream went on (the probe behind them was answered).
    const bool stream_went_on = profile.drops_after_exception || !answers.back().empty();
    for (std::size_t i = 0; i + 1 < pdus.size(); ++i) {
        const Pdu& a = answers[i];
        const std::uint8_t fc = pdus[i][0];
        if (a.empty()) {
            if (stream_went_on && codec::is_supported_function(fc)) profile.silent[fc] = true;
            continue;
        }
        if (a.size() == 2 && a[0] == (fc | codec::kExceptionBit) &&
            a[1] == static_cast<std::uint8_t>(codec::ExceptionCode::IllegalFunction))
            profile.unsupported[fc] = true;
        if (!codec::is_supported_function(fc) && a[0] == fc) profile.extended[fc] = true;
    }
}

// One sub-request of record 0 in file 1: a read of one register, or a write of one (zero).
Pdu file_record_request(const codec::FunctionInfo& info) {
    static constexpr std::uint8_t kZeroWord[] = {0, 0};
    codec::FileSubRequest sub;
    sub.reference_type = codec::limits::kFileReferenceType;
    sub.file_number = 1;
    sub.record_length = 1;
    if (info.writes) sub.record_data = kZeroWord;
    std::array<std::uint8_t, codec::limits::kMaxPdu> payload;
    const codec::EncodeResult written = codec::encode_file_sub_request(sub, payload);
    codec::Request r;
    r.function = codec::to_byte(info.code);
    r.payload = codec::Bytes(payload.data(), written.size);
    return encode_pdu(r);
}

}  // namespace

Pdu canonical_request(const codec::FunctionInfo& info) {
    using codec::RequestShape;
    constexpr std::uint16_t kStateAddress = 0x5FFF;  // where writes change nothing that matters
    static constexpr std::uint8_t kZeroWord[] = {0, 0};
    static constexpr std::uint8_t kQueryData[] = {0x12, 0x34};  // echoed by sub-function 0000
    codec::Request r;
    r.function = codec::to_byte(info.code);
    switch (info.request) {
        case RequestShape::FunctionOnly:
            break;
        case RequestShape::AddressQuantity:
            r.quantity = 1;
            break;
        case RequestShape::SingleCoil:
            r.address = kStateAddress;
            r.value = codec::limits::kCoilOn;
            break;
        case RequestShape::SingleRegister:
            r.address = kStateAddress;
            break;
        case RequestShape::SubFunction:
            r.sub_function =
                static_cast<std::uint16_t>(codec::DiagnosticSubFunction::ReturnQueryData);
            r.payload = kQueryData;
            break;
        case RequestShape::MultipleCoils:
            r.address = kStateAddress;
            r.quantity = 1;
            r.payload = codec::Bytes(kZeroWord, 1);
            break;
        case RequestShape::MultipleRegisters:
            r.address = kStateAddress;
            r.quantity = 1;
            r.payload = kZeroWord;
            break;
        case RequestShape::FileRecords:
            return file_record_request(info);
        case RequestShape::MaskWrite:
            r.address = kStateAddress;
            r.and_mask = 0xFFFF;  // keeps every bit
            break;
        case RequestShape::ReadWriteRegisters:
            r.quantity = 1;
            r.write_address = kStateAddress;
            r.write_quantity = 1;
            r.payload = kZeroWord;
            break;
        case RequestShape::FifoPointer:
            r.address = kStateAddress;
            break;
        case RequestShape::MeiTransport:
            r.mei_type = codec::kMeiReadDeviceId;
            r.device_id_code = 0x01;  // the basic objects
            r.object_id = 0x00;
            break;
    }
    return encode_pdu(r);
}

const std::vector<Pdu>& canonical_requests() {
    static const std::vector<Pdu> canonical = [] {
        std::vector<Pdu> out;
        for (const codec::FunctionInfo& info : codec::public_functions())
            out.push_back(canonical_request(info));
        return out;
    }();
    return canonical;
}

Error discover_target(Connector& target, std::uint8_t unit, int timeout_ms,
                      TargetProfile& profile) {
    profile = TargetProfile{};
    profile.unit = unit;
    profile.framing = target.framing();
    profile.serial_line = target.serial_line();
    if (Error e = choose_probe(target, timeout_ms, profile); !e.ok()) return e;
    // RTU and ASCII send one request at a time: nothing is pipelined to be dropped.
    if (profile.framing == codec::Framing::Mbap)
        profile.drops_after_exception = drops_after_exception(target, profile, timeout_ms);
    std::vector<Pdu> pdus;
    const std::vector<Pdu> answers = ask_every_function(target, profile, timeout_ms, pdus);
    learn_functions(pdus, answers, profile);
    return Error::none();
}

bool wait_for_target_with(RestartCommand& command, Connector& target, const TargetProfile& profile,
                          const std::string& restart_cmd, int wait_ms, int timeout_ms,
                          std::int64_t deadline_ns) {
    const std::int64_t wait_ns = std::int64_t{wait_ms} * net::kNsPerMs;
    std::int64_t deadline = net::now_ns() + wait_ns;
    bool command_running = false, was_running = false;
    if (!restart_cmd.empty()) {
        // One copy at a time: a command still running (a slow restart, or the target itself
        // run in the foreground) is waited for, not started again.
        command_running = was_running = command.running();
        if (!command_running) {
            const Error started = command.start(restart_cmd);
            command_running = started.ok();
            if (!command_running) fmt::print(stderr, "mbstorm fuzz: {}\n", started.text());
        }
        // The wait counts from when the command returns (a `systemctl restart` may take its
        // time); one that does not return (the target in the foreground) gets a minute more.
        if (command_running) deadline += kRestartCommandGraceNs;
    }
    // A command still running from an earlier restart is the target in the foreground: if it
    // returns now, the target it ran is the one that died (sentinels see a death before the
    // process has quite ended), and it is started again, once.
    bool foreground = was_running;
    int backoff_ms = 20;
    for (;;) {
        if (command_running && command.returned()) {
            command_running = false;
            deadline = net::now_ns() + wait_ns;
            if (foreground && command.start(restart_cmd).ok()) {
                command_running = true;
                deadline += kRestartCommandGraceNs;
            }
            foreground = false;
        }
        if (probe_target(target, profile, std::min(timeout_ms, 1000)) == ProbeResult::Ok)
            return true;
        const std::int64_t now = net::now_ns();
        if (now >= deadline || (deadline_ns && now >= deadline_ns)) return false;
        std::this_thread::sleep_for(std::chrono::milliseconds(backoff_ms));
        backoff_ms = std::min(backoff_ms * 3 / 2, 1000);
    }
}

bool wait_for_target(Connector& target, const TargetProfile& profile,
                     const std::string& restart_cmd, int wait_ms, int timeout_ms,
                     std::int64_t deadline_ns) {
    RestartCommand command;
    return wait_for_target_with(command, target, profile, restart_cmd, wait_ms, timeout_ms,
                                deadline_ns);
}

}  // namespace mbstorm::netfuzz
