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

bool save_finding(const Finding& f, const std::string& dir, std::string& error) {
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec) {
        error = fmt::format("cannot create {}: {}", dir, ec.message());
        return false;
    }
    json trace = json::array();
    for (const TraceEvent& e : f.trace) {
        json ev = {{"t_us", e.t_us}, {"conn", e.conn}, {"event", trace_kind_name(e.kind)}};
        if (!e.bytes.empty()) ev["hex"] = to_hex(e.bytes);
        if (!e.note.empty()) ev["note"] = e.note;
        trace.push_back(std::move(ev));
    }
    json j = {
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
        {"profile",
         {{"unit", f.profile.unit},
          {"probe", to_hex(f.profile.probe_pdu)},
          {"unsupported", bytes_list(f.profile.unsupported)},
          {"extended", bytes_list(f.profile.extended)}}},
        {"case", {{"steps", steps_to_json(f.fuzz_case)}}},
        {"original_case", {{"steps", steps_to_json(f.original_case)}}},
        {"trace", trace},
    };
    // The framing the case's bytes are in (MBAP when absent): replay needs the same.
    for (std::size_t t = 0; t < f.profile.unmapped.size(); ++t)
        if (!f.profile.unmapped[t].empty())
            j["profile"]["unmapped"][std::to_string(t)] = f.profile.unmapped[t];
    if (f.profile.refuses_length_mismatch) j["profile"]["refuses_length_mismatch"] = true;
    if (f.profile.one_connection) j["profile"]["one_connection"] = true;
    if (f.profile.marker_address >= 0) j["profile"]["marker_address"] = f.profile.marker_address;
    if (f.profile.framing != codec::Framing::Mbap) {
        j["profile"]["framing"] = codec::framing_name(f.profile.framing);
        j["profile"]["serial_line"] = f.profile.serial_line;
    }
    auto write = [&](const std::string& name, const std::string& text) {
        std::ofstream o(dir + "/" + name, std::ios::trunc);
        o << text;
        if (!o) {
            error = fmt::format("cannot write {}/{}", dir, name);
            return false;
        }
        return true;
    };
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
    return write("finding.json", j.dump(2) + "\n") &&
           write("summary.txt", f.verdict.summary + "\n" + (f.note.empty() ? "" : f.note + "\n")) &&
           write("traffic.txt", traffic.str());
}

bool load_finding(const std::string& path, Finding& out, std::string& error) {
    std::string file = path;
    if (std::filesystem::is_directory(path)) file = path + "/finding.json";
    std::ifstream in(file);
    if (!in) {
        error = fmt::format("cannot read {}", file);
        return false;
    }
    try {
        const json j = json::parse(in);
        out = Finding{};
        out.folder = path;
        out.id = static_cast<std::size_t>(whole_number(j, "id", 0, 0, 1'000'000'000));
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
        out.target = j.value("target", "");
        out.seed = j.contains("seed") && j.at("seed").is_number_unsigned()
                       ? j.at("seed").get<std::uint64_t>()
                       : static_cast<std::uint64_t>(whole_number(j, "seed", 0, 0, INT64_MAX));
        out.timeout_ms = static_cast<int>(whole_number(j, "timeout_ms", 1000, 1, 3'600'000));
        if (j.contains("state_range") && j["state_range"].is_array() &&
            j["state_range"].size() == 2) {
            const auto base = whole_number(j["state_range"][0], "state_range", 0, 0xFFFF);
            const auto span = whole_number(j["state_range"][1], "state_range", 1, 0x10000);
            out.state =
                StateRange{static_cast<std::uint16_t>(base), static_cast<std::uint32_t>(span)};
        }
        out.minimized = j.value("minimized", false);
        out.wrong_fields = j.value("wrong_fields", std::vector<std::string>{});
        out.confirmed = j.value("confirmed", true);
        out.note = j.value("note", "");
        const json& p = j.at("profile");
        out.profile.unit = static_cast<std::uint8_t>(whole_number(p.at("unit"), "unit", 0, 255));
        if (!from_hex(p.at("probe").get<std::string>(), out.profile.probe_pdu) ||
            out.profile.probe_pdu.empty())
            throw std::runtime_error("bad probe");
        parse_list(p.value("unsupported", ""), out.profile.unsupported);
        parse_list(p.value("extended", ""), out.profile.extended);
        const std::string framing = p.value("framing", "mbap");
        if (framing == "rtu")
            out.profile.framing = codec::Framing::Rtu;
        else if (framing == "ascii")
            out.profile.framing = codec::Framing::Ascii;
        else if (framing != "mbap")
            throw std::runtime_error("unknown framing");
        out.profile.serial_line = p.value("serial_line", false);
        out.profile.refuses_length_mismatch = p.value("refuses_length_mismatch", false);
        out.profile.one_connection = p.value("one_connection", false);
        out.profile.marker_address =
            static_cast<std::int32_t>(whole_number(p, "marker_address", -1, 0, 0xFFFF));
        if (p.contains("unmapped") && p["unmapped"].is_object())
            for (const auto& [table, addrs] : p["unmapped"].items()) {
                const std::size_t t = table.size() == 1 && table[0] >= '0' && table[0] <= '3'
                                          ? static_cast<std::size_t>(table[0] - '0')
                                          : out.profile.unmapped.size();
                if (t == out.profile.unmapped.size() || !addrs.is_array())
                    throw std::runtime_error("bad 'unmapped'");
                for (const json& a : addrs)
                    out.profile.unmapped[t].push_back(
                        static_cast<std::uint16_t>(whole_number(a, "unmapped", 0, 0xFFFF)));
            }
        out.hits = static_cast<std::uint64_t>(whole_number(j, "hits", 1, 0, INT64_MAX));
        steps_from_json(j.at("case").at("steps"), out.fuzz_case, kMaxLoadedSteps);
        out.original_case.cls = out.fuzz_case.cls;
        out.original_case.function = out.fuzz_case.function;
        if (j.contains("original_case"))
            steps_from_json(j.at("original_case").at("steps"), out.original_case, kMaxLoadedSteps);
    } catch (const std::exception& e) {
        error = fmt::format("{}: not a finding: {}", file, e.what());
        return false;
    }
    return true;
}

}  // namespace mbstorm::netfuzz
