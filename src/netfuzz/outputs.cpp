#include "netfuzz/outputs.hpp"

#include <fmt/format.h>

#include <map>
#include <nlohmann/json.hpp>

#include "report/xml_escape.hpp"

namespace mbstorm::netfuzz {
namespace {

using report::xml_escape;

using nlohmann::json;

std::string_view sarif_level(Oracle o) {
    return (o == Oracle::Crash || o == Oracle::Hang) ? "error" : "warning";
}

}  // namespace

std::string format_fuzz_json(const CampaignResult& r, const RunInfo& info) {
    json findings = json::array();
    for (const Finding& f : r.findings) {
        findings.push_back({{"id", f.id},
                            {"oracle", oracle_name(f.oracle())},
                            {"function", f.fuzz_case.function},
                            {"class", class_name(f.fuzz_case.cls)},
                            {"summary", f.verdict.summary},
                            {"expected", f.verdict.expected},
                            {"seen", f.verdict.seen},
                            {"folder", f.folder},
                            {"case_number", f.case_number},
                            {"found_after_s", f.found_after_s},
                            {"minimized", f.minimized},
                            {"confirmed", f.confirmed},
                            {"note", f.note}});
    }
    json classes = json::object();
    for (std::size_t i = 0; i < r.cases_by_class.size(); ++i)
        if (r.cases_by_class[i])
            classes[std::string(class_name(static_cast<MutationClass>(i)))] = r.cases_by_class[i];
    const json j = {
        {"schema", 1},
        {"tool", "mbstorm fuzz"},
        {"target", info.target},
        {"seed", info.seed},
        {"generator", info.naive ? "naive" : "structured"},
        {"started", r.started},
        {"error", r.error},
        {"cases", r.cases},
        {"seconds", r.seconds},
        {"cases_per_second", r.seconds > 0 ? static_cast<double>(r.cases) / r.seconds : 0.0},
        {"batched_cases", r.batched_cases},
        {"isolated_runs", r.isolated_runs},
        {"duplicates", r.duplicates},
        {"unconfirmed", r.unconfirmed},
        {"restarts", r.restarts},
        {"target_lost", r.target_lost},
        {"stop_reason", r.stop_reason},
        {"cases_by_class", classes},
        {"findings", findings}};
    return j.dump(2) + "\n";
}

std::string format_fuzz_junit(const CampaignResult& r, const RunInfo& info) {
    // One test case per mutation class that ran; each finding is a failure of its class.
    std::map<std::string, std::vector<const Finding*>> by_class;
    for (std::size_t i = 0; i < r.cases_by_class.size(); ++i)
        if (r.cases_by_class[i]) by_class[std::string(class_name(static_cast<MutationClass>(i)))];
    for (const Finding& f : r.findings)
        by_class[std::string(class_name(f.fuzz_case.cls))].push_back(&f);
    std::size_t failures = 0;
    for (auto& [k, v] : by_class) failures += v.empty() ? 0 : 1;
    std::string x = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
    x += fmt::format(
        "<testsuites name=\"mbstorm fuzz\" tests=\"{}\" failures=\"{}\" time=\"{:.3f}\">\n",
        by_class.size(), failures, r.seconds);
    x +=
        fmt::format("  <testsuite name=\"fuzz {}\" tests=\"{}\" failures=\"{}\" time=\"{:.3f}\">\n",
                    xml_escape(info.target), by_class.size(), failures, r.seconds);
    for (const auto& [cls, list] : by_class) {
        x +=
            fmt::format("    <testcase classname=\"mbstorm.fuzz\" name=\"{}\">\n", xml_escape(cls));
        if (!list.empty()) {
            std::string body;
            for (const Finding* f : list)
                body += fmt::format("{}\nexpected: {}\nseen: {}\n{}folder: {}\n\n",
                                    f->verdict.summary, f->verdict.expected, f->verdict.seen,
                                    f->note.empty() ? "" : "note: " + f->note + "\n", f->folder);
            x += fmt::format(
                "      <failure message=\"{} finding(s)\" type=\"{}\">{}</failure>\n", list.size(),
                xml_escape(std::string(oracle_name(list.front()->oracle()))), xml_escape(body));
        }
        x += "    </testcase>\n";
    }
    if (!r.started || r.target_lost) {
        x += fmt::format(
            "    <testcase classname=\"mbstorm.fuzz\" name=\"target\">\n      <error "
            "message=\"{}\"/>\n    </testcase>\n",
            xml_escape(r.started ? r.stop_reason : r.error));
    }
    x += "  </testsuite>\n</testsuites>\n";
    return x;
}

std::string format_fuzz_sarif(const CampaignResult& r, const RunInfo& info) {
    json rules = json::array();
    for (std::size_t i = 1; i < static_cast<std::size_t>(Oracle::Count); ++i) {
        const auto name = std::string(oracle_name(static_cast<Oracle>(i)));
        rules.push_back(
            {{"id", name}, {"shortDescription", {{"text", "Modbus TCP target: " + name}}}});
    }
    json results = json::array();
    for (const Finding& f : r.findings) {
        json result = {
            {"ruleId", oracle_name(f.oracle())},
            {"level", sarif_level(f.oracle())},
            {"message",
             {{"text", f.verdict.summary + " | expected: " + f.verdict.expected + " | seen: " +
                           f.verdict.seen + (f.note.empty() ? "" : " | note: " + f.note)}}},
            {"partialFingerprints", {{"mbstormKey", f.key()}}},
            {"properties",
             {{"function", f.fuzz_case.function},
              {"class", class_name(f.fuzz_case.cls)},
              {"confirmed", f.confirmed}}}};
        if (!f.folder.empty())
            result["locations"] =
                json::array({{{"physicalLocation",
                               {{"artifactLocation", {{"uri", f.folder + "/finding.json"}}}}}}});
        results.push_back(std::move(result));
    }
    const json j = {
        {"$schema", "https://json.schemastore.org/sarif-2.1.0.json"},
        {"version", "2.1.0"},
        {"runs", json::array({{{"tool",
                                {{"driver",
                                  {{"name", "mbstorm fuzz"},
                                   {"informationUri", "https://github.com/mbstorm/mbstorm"},
                                   {"rules", rules}}}}},
                               {"properties",
                                {{"target", info.target}, {"seed", info.seed}, {"cases", r.cases}}},
                               {"results", results}}})}};
    return j.dump(2) + "\n";
}

std::string format_fuzz_summary(const CampaignResult& r, const RunInfo& info) {
    std::string s = fmt::format("\nmbstorm fuzz summary: target {}, seed {}, {} generator\n",
                                info.target, info.seed, info.naive ? "naive" : "structured");
    s += fmt::format("  {} cases in {:.1f} s ({:.0f} cases/s); {} batched, {} isolated runs\n",
                     r.cases, r.seconds,
                     r.seconds > 0 ? static_cast<double>(r.cases) / r.seconds : 0.0,
                     r.batched_cases, r.isolated_runs);
    s += fmt::format(
        "  time: {:.1f} s pipelined, {:.1f} s isolated (transport, stateful, suspects)\n",
        r.batch_seconds, r.isolated_seconds);
    s += fmt::format("  target restarts: {}; duplicates suppressed: {}; unconfirmed suspects: {}\n",
                     r.restarts, r.duplicates, r.unconfirmed);
    s += fmt::format("  stopped: {}\n", r.stop_reason);
    if (r.findings.empty()) {
        s += "  no findings\n";
    } else {
        s += fmt::format("  {} finding(s):\n", r.findings.size());
        for (const Finding& f : r.findings)
            s += fmt::format("  #{} {:<18} {}\n      {}{}\n", f.id, oracle_name(f.oracle()),
                             f.verdict.summary,
                             f.note.empty() ? std::string() : "note: " + f.note + "\n      ",
                             f.folder.empty() ? std::string("(not saved)") : f.folder);
    }
    return s;
}

}  // namespace mbstorm::netfuzz
