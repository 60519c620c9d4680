#include "netfuzz/outputs.hpp"

#include <fmt/format.h>

#include <algorithm>
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

namespace {

// Grey-box runs: edges over time, the corpus; null for black-box ones.
json coverage_json(const CampaignResult& r) {
    if (!r.coverage) return nullptr;
    json over_time = json::array();
    for (const auto& [seconds, edges] : r.edges_over_time) over_time.push_back({seconds, edges});
    json by_function = json::object();
    for (const auto& [fc, edges] : r.edges_by_function)
        by_function[fmt::format("0x{:02X}", fc)] = edges;
    return {{"edges", r.coverage_edges},
            {"corpus", r.corpus_size},
            {"compared_constants", r.compared_constants},
            {"resumed", r.resumed},
            {"calibration_runs", r.calibration_runs},
            {"unstable_cells", r.unstable_cells},
            {"edges_by_function", by_function},
            {"corpus_error", r.corpus_error},
            {"edges_over_time", over_time}};
}

json baseline_name(BaselineState b) {
    switch (b) {
        case BaselineState::None:
            return nullptr;
        case BaselineState::New:
            return "new";
        case BaselineState::Known:
            return "known";
    }
    return nullptr;
}

json finding_json(const Finding& f) {
    return {{"id", f.id},
            {"oracle", oracle_name(f.oracle())},
            {"rule", f.verdict.rule},
            {"root_cause", f.key()},
            {"function", f.function() >= 0 ? json(f.function()) : json(nullptr)},
            {"class", class_name(f.fuzz_case.cls)},
            {"hits", f.hits},
            {"variants", f.variants},
            {"minimize_note", f.minimize_note},
            {"wrong_fields", f.wrong_fields},
            {"restarts", f.restarts},
            {"summary", f.verdict.summary},
            {"expected", f.verdict.expected},
            {"seen", f.verdict.seen},
            {"folder", f.folder},
            {"case_number", f.case_number},
            {"found_after_s", f.found_after_s},
            {"minimized", f.minimized},
            {"confirmed", f.confirmed},
            {"baseline", baseline_name(f.baseline)},
            {"note", f.note}};
}

json cases_by_class_json(const CampaignResult& r) {
    json classes = json::object();
    for (std::size_t i = 0; i < r.cases_by_class.size(); ++i)
        if (r.cases_by_class[i])
            classes[std::string(class_name(static_cast<MutationClass>(i)))] = r.cases_by_class[i];
    return classes;
}

json death_marker_json(const CampaignResult& r) {
    if (r.death_marker < 0) return json();
    return {{"address", r.death_marker},
            {"initial", r.death_marker_initial},
            {"value", r.death_marker_value}};
}

json baseline_json(const CampaignResult& r) {
    if (r.baseline_file.empty()) return nullptr;
    return {{"file", r.baseline_file},
            {"new", r.new_findings()},
            {"known", r.findings.size() - r.new_findings()},
            {"absent", r.baseline_absent}};
}

}  // namespace

std::string format_fuzz_json(const CampaignResult& r, const RunInfo& info) {
    json findings = json::array();
    for (const Finding& f : r.findings) findings.push_back(finding_json(f));
    const json j = {
        {"schema", 1},
        {"tool", "mbstorm fuzz"},
        {"target", info.target},
        {"seed", info.seed},
        {"generator", info.naive ? "naive" : "structured"},
        {"started", r.started},
        {"error", r.error.text()},
        {"cases", r.cases},
        {"seconds", r.seconds},
        {"cases_per_second", r.seconds > 0 ? static_cast<double>(r.cases) / r.seconds : 0.0},
        {"batched_cases", r.batched_cases},
        {"isolated_runs", r.isolated_runs},
        {"duplicates", r.duplicates},
        {"unconfirmed", r.unconfirmed},
        {"skipped_known", r.skipped_known},
        {"first_looks", r.first_looks},
        {"requeued", r.requeued},
        {"restarts", r.restarts},
        {"deaths", r.deaths},
        {"unattributed_deaths", r.unattributed_deaths},
        {"answers", r.answers},
        {"busy_answers", r.busy_answers},
        {"slowed_for_busy", r.slowed_for_busy},
        {"suspects_left", r.suspects_left},
        {"findings_not_minimized", r.findings_not_minimized},
        {"capacity_held", r.capacity_held},
        {"drops_after_exception", r.profile.drops_after_exception},
        {"target_lost", r.target_lost},
        {"stop_reason", r.stop_reason},
        {"cases_by_class", cases_by_class_json(r)},
        {"model", r.model.source.empty() ? json(nullptr) : json::parse(model_to_json(r.model))},
        {"learn_seconds", r.learn_seconds},
        {"learn_requests", r.learn_requests},
        {"refine_seconds", r.refine_seconds},
        {"refine_requests", r.refine_requests},
        {"refine_done", r.refine_done},
        {"death_watch", r.death_watch},
        {"one_connection_at_a_time", r.profile.one_connection},
        {"not_sent_one_connection", r.not_sent_one_connection},
        {"death_marker", death_marker_json(r)},
        {"rationed", r.rationed},
        {"coverage", coverage_json(r)},
        {"baseline", baseline_json(r)},
        {"findings", findings}};
    return j.dump(2) + "\n";
}

std::string format_fuzz_junit(const CampaignResult& r, const RunInfo& info) {
    // One test case per mutation class that ran; each finding is a failure of its class.
    std::map<std::string, std::vector<const Finding*>> by_class;
    for (std::size_t i = 0; i < r.cases_by_class.size(); ++i)
        if (r.cases_by_class[i]) by_class[std::string(class_name(static_cast<MutationClass>(i)))];
    for (const Finding& f : r.findings)
        if (f.baseline != BaselineState::Known)
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
            xml_escape(r.started ? r.stop_reason : r.error.text()));
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
             {{"function", f.function()},
              {"rule", f.verdict.rule},
              {"class", class_name(f.fuzz_case.cls)},
              {"hits", f.hits},
              {"confirmed", f.confirmed}}}};
        if (f.baseline != BaselineState::None)
            result["baselineState"] = f.baseline == BaselineState::Known ? "unchanged" : "new";
        if (!f.folder.empty())
            // GitHub code scanning shows a result only with a region (startLine at least).
            result["locations"] =
                json::array({{{"physicalLocation",
                               {{"artifactLocation", {{"uri", f.folder + "/finding.json"}}},
                                {"region", {{"startLine", 1}}}}}}});
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

namespace {

// The root causes, worst first (crash, hang, close, malformed response, spec deviation), each
// with its rule, hits, variants, notes and folder.
std::string format_root_causes(const CampaignResult& r) {
    std::string s;
    std::vector<const Finding*> ranked;
    for (const Finding& f : r.findings) ranked.push_back(&f);
    std::stable_sort(ranked.begin(), ranked.end(),
                     [](const Finding* a, const Finding* b) { return a->oracle() < b->oracle(); });
    s += fmt::format("  {} root cause(s):\n", r.findings.size());
    for (const Finding* f : ranked) {
        s += fmt::format("  #{} {:<18} {}{}\n      rule {}; {} hit(s)", f->id,
                         oracle_name(f->oracle()), f->verdict.summary,
                         f->baseline == BaselineState::Known ? " (known: in the baseline)" : "",
                         f->verdict.rule, f->hits);
        std::string variants;
        std::size_t shown = 0;
        for (const auto& [v, n] : f->variants) {
            if (shown++ == 6) {
                variants += fmt::format(", ... {} more", f->variants.size() - 6);
                break;
            }
            variants += fmt::format("{}{} x{}", variants.empty() ? "" : ", ", v, n);
        }
        if (!variants.empty()) s += " in " + variants;
        s += "\n      ";
        if (!f->note.empty()) s += "note: " + f->note + "\n      ";
        if (!f->minimize_note.empty()) s += f->minimize_note + "\n      ";
        s += f->folder.empty() ? std::string("(not saved)") : f->folder;
        s += "\n";
    }
    return s;
}

// Grey-box runs: edges, corpus and constants, and the corpus's troubles.
std::string format_coverage(const CampaignResult& r) {
    std::string s;
    if (r.coverage)
        s += fmt::format(
            "  coverage: {} edges; corpus {} case(s); {} constant(s) from the target's "
            "comparisons; {} map cell(s) unstable (timing, not input) in {} calibration "
            "run(s)\n",
            r.coverage_edges, r.corpus_size, r.compared_constants, r.unstable_cells,
            r.calibration_runs);
    if (!r.edges_by_function.empty()) {
        std::string by;
        for (const auto& [fc, edges] : r.edges_by_function)
            by += fmt::format("{}0x{:02X} {}", by.empty() ? "" : ", ", fc, edges);
        s += fmt::format("  new edges by the function code that reached them first: {}\n", by);
    }
    if (r.resumed) s += fmt::format("  corpus resumed: {} saved entries run first\n", r.resumed);
    if (!r.corpus_error.empty())
        s += fmt::format("  WARNING: the corpus is no longer saved: {}\n", r.corpus_error);
    return s;
}

// The device model the cases were made from, indented (empty when there is none).
std::string format_model_lines(const CampaignResult& r) {
    if (r.model.source.empty()) return {};
    std::string model = format_model(r.model);
    if (r.model.source == "learned")
        model.insert(model.find(')'),
                     fmt::format("; {} requests in {:.2f} s", r.learn_requests, r.learn_seconds));
    if (r.refine_requests)
        model.insert(model.find(')'), fmt::format("; refined during the run: {} requests in "
                                                  "{:.2f} s{}",
                                                  r.refine_requests, r.refine_seconds,
                                                  r.refine_done ? ", every gap asked" : ""));
    for (std::size_t at = 0; at < model.size(); at = model.find('\n', at) + 1)
        model.insert(at, "  ");
    return model;
}

// How the target's deaths were told: a marker register, idle sentinels, or neither.
std::string format_death_detection(const CampaignResult& r) {
    if (r.death_marker >= 0)
        return fmt::format(
            "  deaths seen by a marker register: holding {} was given {:04X} (it held {:04X}); "
            "lost after a case that did not write it, the process restarted\n",
            r.death_marker, r.death_marker_value, r.death_marker_initial);
    return fmt::format("  deaths seen by idle sentinel connections: {}\n",
                       r.death_watch ? "yes (a crash is a crash even when a supervisor "
                                       "restarts the target)"
                                     : "no (the target does not serve an idle connection "
                                       "beside another, or a serial line; and no register of "
                                       "a learned map keeps what is written)");
}

}  // namespace

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
    s += format_coverage(r);
    s += fmt::format(
        "  target deaths: {} ({} restarts, {} not repeatable alone); repeats of known root "
        "causes: {}; cases skipped as known crash/hang: {}; unconfirmed suspects: {}\n",
        r.deaths, r.restarts, r.unattributed_deaths, r.duplicates, r.skipped_known, r.unconfirmed);
    s += format_model_lines(r);
    s += format_death_detection(r);
    if (r.profile.one_connection)
        s += fmt::format(
            "  the target serves one connection at a time: {} case(s) needing two at once were "
            "not sent\n",
            r.not_sent_one_connection);
    if (r.rationed)
        s += fmt::format(
            "  {} case(s) owed an exception the target pauses after were not sent (each kind "
            "once, then 1 in 32, the pauses within a quarter of the run)\n",
            r.rationed);
    if (r.profile.drops_after_exception)
        s += "  the target drops requests pipelined behind an exception: those were sent one "
             "at a time\n";
    if (r.slowed_for_busy || (r.answers >= 16 && r.busy_answers * 4 > r.answers))
        s += fmt::format(
            "  WARNING: {} of {} pipelined answers were exception 06 (busy): those cases were "
            "wasted; the lanes were thinned (fuzz with fewer --connections, or a quieter "
            "target)\n",
            r.busy_answers, r.answers);
    if (r.capacity_held)
        s += fmt::format("  capacity check: held {} connections\n", r.capacity_held);
    if (r.suspects_left || r.findings_not_minimized)
        s += fmt::format(
            "  cut short by the deadline: {} suspect(s) not re-run, {} finding(s) not "
            "minimised\n",
            r.suspects_left, r.findings_not_minimized);
    s += fmt::format("  stopped: {}\n", r.stop_reason);
    if (!r.baseline_file.empty())
        s += fmt::format(
            "  baseline {}: {} new, {} known (not failing the run), {} of it not seen "
            "this run\n",
            r.baseline_file, r.new_findings(), r.findings.size() - r.new_findings(),
            r.baseline_absent.size());
    if (r.findings.empty()) {
        s += "  no findings\n";
        return s;
    }
    return s + format_root_causes(r);
}

}  // namespace mbstorm::netfuzz
