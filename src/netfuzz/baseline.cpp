#include "netfuzz/baseline.hpp"

#include <fmt/format.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

namespace mbstorm::netfuzz {
namespace {

using nlohmann::json;

// Each key is a string: anything else means the file is not what it claims to be.
bool take_key(const json& key, Baseline& out, std::string& error) {
    if (!key.is_string() || key.get<std::string>().empty()) {
        error = fmt::format("{}: a root cause is not a non-empty string: {}", out.file,
                            key.dump().substr(0, 60));
        return false;
    }
    out.keys.insert(key.get<std::string>());
    return true;
}

bool from_summary(const json& j, Baseline& out, std::string& error) {
    if (!j["findings"].is_array()) {
        error = out.file + ": \"findings\" is not a list";
        return false;
    }
    for (const json& f : j["findings"]) {
        if (!f.is_object() || !f.contains("root_cause")) {
            error = out.file + ": a finding has no \"root_cause\"";
            return false;
        }
        if (!take_key(f["root_cause"], out, error)) return false;
    }
    return true;
}

bool from_sarif(const json& j, Baseline& out, std::string& error) {
    for (const json& run : j["runs"].is_array() ? j["runs"] : json::array()) {
        if (!run.is_object() || !run.contains("results")) continue;
        if (!run["results"].is_array()) {
            error = out.file + ": a run's \"results\" is not a list";
            return false;
        }
        for (const json& res : run["results"]) {
            const json* key = nullptr;
            if (res.is_object() && res.contains("partialFingerprints") &&
                res["partialFingerprints"].is_object() &&
                res["partialFingerprints"].contains("mbstormKey"))
                key = &res["partialFingerprints"]["mbstormKey"];
            if (!key) {
                error = out.file + ": a result has no partialFingerprints.mbstormKey";
                return false;
            }
            if (!take_key(*key, out, error)) return false;
        }
    }
    return true;
}

}  // namespace

Result<Baseline> load_baseline(const std::string& path) {
    Baseline out{path, {}};
    std::ifstream in(path);
    if (!in) return Error(open_failure(path), fmt::format("cannot read --baseline {}", path));
    std::stringstream text;
    text << in.rdbuf();
    const json j = json::parse(text.str(), nullptr, false);
    if (j.is_discarded() || !j.is_object()) {
        return Error(ErrorCode::InvalidInput,
                     fmt::format("--baseline {}: not a JSON object (give an earlier run's --json "
                                 "or --sarif file)",
                                 path));
    }
    if (!j.contains("findings") && !j.contains("runs")) {
        return Error(ErrorCode::InvalidInput,
                     fmt::format("--baseline {}: neither a fuzz --json summary (\"findings\") "
                                 "nor a SARIF log (\"runs\")",
                                 path));
    }
    std::string error;
    const bool read =
        j.contains("findings") ? from_summary(j, out, error) : from_sarif(j, out, error);
    if (!read) return Error(ErrorCode::InvalidInput, std::move(error));
    return out;
}

void apply_baseline(const Baseline& b, CampaignResult& r) {
    r.baseline_file = b.file;
    std::set<std::string> seen;
    for (Finding& f : r.findings) {
        f.baseline = b.keys.count(f.key()) ? BaselineState::Known : BaselineState::New;
        seen.insert(f.key());
    }
    r.baseline_absent.clear();
    for (const std::string& k : b.keys)
        if (!seen.count(k)) r.baseline_absent.push_back(k);
}

}  // namespace mbstorm::netfuzz
