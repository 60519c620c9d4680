#include "netfuzz/finding.hpp"

#include "netfuzz/case_json.hpp"
#include "netfuzz/rules.hpp"

#include <fmt/format.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

namespace mbstorm::netfuzz {
namespace {

using nlohmann::json;

// A sanity bound on what a finding file may ask us to send: room for a whole pipelined batch
// (one step per frame: up to 64 connections x 48 cases, coalesced cases holding up to 17).
constexpr std::size_t kMaxLoadedSteps = 64 * 48 * 17;

std::string bytes_list(const std::array<bool, 256>& flags) {
    std::string s;
    for (unsigned i = 0; i < 256; ++i)
        if (flags[i]) s += fmt::format("{}{:02X}", s.empty() ? "" : " ", i);
    return s;
}

void parse_list(const std::string& s, std::array<bool, 256>& flags) {
    std::vector<std::uint8_t> v;
    std::string compact;
    for (char c : s)
        if (c != ' ') compact += c;
    if (from_hex(compact, v))
        for (auto b : v) flags[b] = true;
}

}  // namespace

namespace {
// A stream lost after a request of the wrong length shows as a close, silence or a stray
// answer depending on timing: one root cause under any of those oracles.
bool any_oracle(const std::string& stem) {
    return stem == kStreamLostRule;
}
// A frame in pieces acted on before it was whole (kAnswersPartialFrameRule): a stray answer,
// a close or silence on the split request.
bool partial_frame_family(const std::string& rule) {
    return rule == kAnswersPartialFrameRule || rule == kClosesOnPartialFrameRule ||
           rule == unanswered_rule(true, kPartialFrameCulprit) ||
           rule == unanswered_rule(false, kPartialFrameCulprit);
}
}  // namespace

std::string root_cause_key(const Verdict& v) {
    if (any_oracle(rule_stem(v.rule))) return fmt::format("stream:{}", v.rule);
    if (partial_frame_family(v.rule)) return fmt::format("stream:{}", kPartialFrameFamily);
    return fmt::format("{}:{}", oracle_name(v.oracle), v.rule);
}

std::string rule_stem(const std::string& rule) {
    const auto cut = rule.find_first_of("(/");
    return cut == std::string::npos ? rule : rule.substr(0, cut);
}

bool same_fault(const Verdict& a, const Verdict& b) {
    if (partial_frame_family(a.rule) && partial_frame_family(b.rule)) return true;
    const std::string stem = rule_stem(a.rule);
    return stem == rule_stem(b.rule) && (a.oracle == b.oracle || any_oracle(stem));
}

std::string to_hex(const std::vector<std::uint8_t>& bytes) {
    std::string s;
    s.reserve(bytes.size() * 2);
    for (auto b : bytes) s += fmt::format("{:02x}", b);
    return s;
}

bool from_hex(const std::string& text, std::vector<std::uint8_t>& out) {
    out.clear();
    std::string t;
    for (char c : text)
        if (!std::isspace(static_cast<unsigned char>(c))) t += c;
    if (t.size() % 2) return false;
    auto nib = [](char c) -> int {
        if (c >= '0' && c <= '9') return c - '0';
        if (c >= 'a' && c <= 'f') return c - 'a' + 10;
        if (c >= 'A' && c <= 'F') return c - 'A' + 10;
        return -1;
    };
    for (std::size_t i = 0; i < t.size(); i += 2) {
        const int hi = nib(t[i]), lo = nib(t[i + 1]);
        if (hi < 0 || lo < 0) return false;
        out.push_back(static_cast<std::uint8_t>(hi << 4 | lo));
    }
    return true;
}

namespace {

json trace_json(const std::vector<TraceEvent>& events) {
    json trace = json::array();
    for (const TraceEvent& e : events) {
        json ev = {{"t_us", e.t_us}, {"conn", e.conn}, {"event", trace_kind_name(e.kind)}};
        if (!e.bytes.empty()) ev["hex"] = to_hex(e.bytes);
        if (!e.note.empty()) ev["note"] = e.note;
        trace.push_back(std::move(ev));
    }
    return trace;
}

// What replay needs to know of the target; facts that are the default are left out.
json profile_json(const TargetProfile& profile) {
    json p = {{"unit", profile.unit},
              {"probe", to_hex(profile.probe_pdu)},
              {"unsupported", bytes_list(profile.unsupported)},
              {"extended", bytes_list(profile.extended)}};
    for (std::size_t t = 0; t < profile.unmapped.size(); ++t)
        if (!profile.unmapped[t].empty()) p["unmapped"][std::to_string(t)] = profile.unmapped[t];
    if (profile.refuses_length_mismatch) p["refuses_length_mismatch"] = true;
    // What follows an exception is dropped on purpose: replay blames a silence behind one as
    // the run did (else a frame of the wrong length answered 03 reads as a lost stream).
    if (profile.drops_after_exception) p["drops_after_exception"] = true;
    if (profile.one_connection) p["one_connection"] = true;
    if (profile.answers_protocol_id) p["answers_protocol_id"] = true;
    if (profile.marker_address >= 0) p["marker_address"] = profile.marker_address;
    // The framing the case's bytes are in (MBAP when absent): replay needs the same.
    if (profile.framing != codec::Framing::Mbap) {
        p["framing"] = codec::framing_name(profile.framing);
        p["serial_line"] = profile.serial_line;
    }
    return p;
}

json finding_json(const Finding& f) {
    return {
        {"schema", 1},
        {"id", f.id},
        {"oracle", oracle_name(f.verdict.oracle)},
        {"rule", f.verdict.rule},
        {"root_cause", f.key()},
        {"function", f.function()},
        {"class", class_name(f.fuzz_case.cls)},
        {"hits", f.hits},
        {"variants", f.variants},
        {"summary", f.verdict.summary},
        {"expected", f.verdict.expected},
        {"seen", f.verdict.seen},
        {"target", f.target},
        {"seed", f.seed},
        {"case_number", f.case_number},
        {"found_after_s", f.found_after_s},
        {"minimized", f.minimized},
        {"minimize_note", f.minimize_note},
        {"wrong_fields", f.wrong_fields},
        {"confirmed", f.confirmed},
        {"note", f.note},
        {"original_steps", f.original_steps},
        {"timeout_ms", f.timeout_ms},
        {"state_range", {f.state.base, f.state.span}},
        {"profile", profile_json(f.profile)},
        {"case", {{"steps", steps_to_json(f.fuzz_case)}}},
        {"original_case", {{"steps", steps_to_json(f.original_case)}}},
        {"trace", trace_json(f.trace)},
    };
}

// traffic.txt: the verdict, then one line per trace event.
std::string traffic_text(const Finding& f) {
    std::ostringstream traffic;
    traffic << "# " << f.verdict.summary << "\n# expected: " << f.verdict.expected
            << "\n# seen:     " << f.verdict.seen << "\n";
    if (!f.note.empty()) traffic << "# note:     " << f.note << "\n";
    traffic << "# time(us) conn event bytes\n";
    for (const TraceEvent& e : f.trace) {
        traffic << fmt::format("{:>9} {:>4} {:<14} {}{}\n", e.t_us,
                               e.conn == 255 ? std::string("new") : std::to_string(e.conn),
                               trace_kind_name(e.kind), hex(e.bytes, 300),
                               e.note.empty() ? "" : "  (" + e.note + ")");
    }
    return traffic.str();
}

Error write_text(const std::string& dir, const std::string& name, const std::string& text) {
    std::ofstream o(dir + "/" + name, std::ios::trunc);
    o << text;
    if (!o) return Error(ErrorCode::Io, fmt::format("cannot write {}/{}", dir, name));
    return Error::none();
}

}  // namespace

Error save_finding(const Finding& f, const std::string& dir) {
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec) return Error(ErrorCode::Io, fmt::format("cannot create {}: {}", dir, ec.message()));
    if (Error e = write_text(dir, "finding.json", finding_json(f).dump(2) + "\n"); !e.ok())
        return e;
    const std::string summary = f.verdict.summary + "\n" + (f.note.empty() ? "" : f.note + "\n");
    if (Error e = write_text(dir, "summary.txt", summary); !e.ok()) return e;
    return write_text(dir, "traffic.txt", traffic_text(f));
}

namespace {

// The verdict's fields and the case's class and function code.
void load_verdict(const json& j, Finding& out) {
    if (!oracle_from_name(j.at("oracle").get<std::string>(), out.verdict.oracle))
        throw std::runtime_error("unknown oracle");
    out.verdict.rule = j.value("rule", "");
    out.verdict.summary = j.value("summary", "");
    out.verdict.expected = j.value("expected", "");
    out.verdict.seen = j.value("seen", "");
    out.verdict.culprit_fc = j.at("function").is_null()
                                 ? -1
                                 : static_cast<int>(whole_number(j, "function", -1, -1, 255));
    if (out.verdict.culprit_fc >= 0)
        out.fuzz_case.function = static_cast<std::uint8_t>(out.verdict.culprit_fc);
    if (!class_from_name(j.at("class").get<std::string>(), out.fuzz_case.cls))
        throw std::runtime_error("unknown class");
}

// Where and how the finding was run and what became of it.
void load_run(const json& j, Finding& out) {
    out.target = j.value("target", "");
    out.seed = j.contains("seed") && j.at("seed").is_number_unsigned()
                   ? j.at("seed").get<std::uint64_t>()
                   : static_cast<std::uint64_t>(whole_number(j, "seed", 0, 0, INT64_MAX));
    out.timeout_ms = static_cast<int>(whole_number(j, "timeout_ms", 1000, 1, 3'600'000));
    if (j.contains("state_range") && j["state_range"].is_array() && j["state_range"].size() == 2) {
        const auto base = whole_number(j["state_range"][0], "state_range", 0, 0xFFFF);
        const auto span = whole_number(j["state_range"][1], "state_range", 1, 0x10000);
        out.state = StateRange{static_cast<std::uint16_t>(base), static_cast<std::uint32_t>(span)};
    }
    out.minimized = j.value("minimized", false);
    out.wrong_fields = j.value("wrong_fields", std::vector<std::string>{});
    out.confirmed = j.value("confirmed", true);
    out.note = j.value("note", "");
}

codec::Framing framing_from_text(const std::string& framing) {
    if (framing == "rtu") return codec::Framing::Rtu;
    if (framing == "ascii") return codec::Framing::Ascii;
    if (framing != "mbap") throw std::runtime_error("unknown framing");
    return codec::Framing::Mbap;
}

void load_unmapped(const json& p, TargetProfile& out) {
    if (!p.contains("unmapped") || !p["unmapped"].is_object()) return;
    for (const auto& [table, addrs] : p["unmapped"].items()) {
        const std::size_t t = table.size() == 1 && table[0] >= '0' && table[0] <= '3'
                                  ? static_cast<std::size_t>(table[0] - '0')
                                  : out.unmapped.size();
        if (t == out.unmapped.size() || !addrs.is_array())
            throw std::runtime_error("bad 'unmapped'");
        for (const json& a : addrs)
            out.unmapped[t].push_back(
                static_cast<std::uint16_t>(whole_number(a, "unmapped", 0, 0xFFFF)));
    }
}

void load_profile(const json& p, TargetProfile& out) {
    out.unit = static_cast<std::uint8_t>(whole_number(p.at("unit"), "unit", 0, 255));
    if (!from_hex(p.at("probe").get<std::string>(), out.probe_pdu) || out.probe_pdu.empty())
        throw std::runtime_error("bad probe");
    parse_list(p.value("unsupported", ""), out.unsupported);
    parse_list(p.value("extended", ""), out.extended);
    out.framing = framing_from_text(p.value("framing", "mbap"));
    out.serial_line = p.value("serial_line", false);
    out.refuses_length_mismatch = p.value("refuses_length_mismatch", false);
    out.drops_after_exception = p.value("drops_after_exception", false);
    out.one_connection = p.value("one_connection", false);
    out.answers_protocol_id = p.value("answers_protocol_id", false);
    out.marker_address =
        static_cast<std::int32_t>(whole_number(p, "marker_address", -1, 0, 0xFFFF));
    load_unmapped(p, out);
}

}  // namespace

Result<Finding> load_finding(const std::string& path) {
    std::string file = path;
    if (std::filesystem::is_directory(path)) file = path + "/finding.json";
    std::ifstream in(file);
    if (!in) return Error(open_failure(file), fmt::format("cannot read {}", file));
    // The JSON reader throws (nlohmann's, and the loaders' refusals above): caught here.
    Finding out;
    try {
        const json j = json::parse(in);
        out.folder = path;
        out.id = static_cast<std::size_t>(whole_number(j, "id", 0, 0, 1'000'000'000));
        load_verdict(j, out);
        load_run(j, out);
        load_profile(j.at("profile"), out.profile);
        out.hits = static_cast<std::uint64_t>(whole_number(j, "hits", 1, 0, INT64_MAX));
        steps_from_json(j.at("case").at("steps"), out.fuzz_case, kMaxLoadedSteps);
        out.original_case.cls = out.fuzz_case.cls;
        out.original_case.function = out.fuzz_case.function;
        if (j.contains("original_case"))
            steps_from_json(j.at("original_case").at("steps"), out.original_case, kMaxLoadedSteps);
    } catch (const std::exception& e) {
        return Error(ErrorCode::InvalidInput, fmt::format("not a finding: {}", e.what()), file);
    }
    return out;
}

}  // namespace mbstorm::netfuzz
