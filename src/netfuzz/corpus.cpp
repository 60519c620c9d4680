#include "netfuzz/corpus.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "netfuzz/case_json.hpp"
#include "netfuzz/finding.hpp"

namespace mbstorm::netfuzz {
namespace {

using nlohmann::json;
namespace fs = std::filesystem;

constexpr std::size_t kMaxSteps = 4096;
constexpr std::size_t kMaxEntryBytes = 1 << 20;

Case case_from(const json& j) {
    Case c;
    if (!class_from_name(j.at("class").get<std::string>(), c.cls))
        throw std::runtime_error("unknown class");
    c.function = static_cast<std::uint8_t>(whole_number(j, "function", 0, 0, 255));
    steps_from_json(j.at("steps"), c, kMaxSteps);
    if (c.steps.empty()) throw std::runtime_error("no steps");
    return c;
}

}  // namespace

Error save_corpus_entry(const std::string& dir, std::size_t index, const Case& c) {
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec) return Error(ErrorCode::Io, fmt::format("cannot create {}: {}", dir, ec.message()));
    const json j = {
        {"class", class_name(c.cls)}, {"function", c.function}, {"steps", steps_to_json(c)}};
    const std::string path = fmt::format("{}/{:06}.json", dir, index);
    std::ofstream out(path);
    out << j.dump(1) << "\n";
    if (!out) return Error(ErrorCode::Io, fmt::format("cannot write {}", path));
    return Error::none();
}

Result<std::vector<Case>> load_corpus(const std::string& dir) {
    std::vector<Case> out;
    std::error_code ec;
    if (!fs::exists(dir, ec)) return out;
    std::vector<fs::path> files;
    for (const auto& e : fs::directory_iterator(dir, ec))
        if (e.path().extension() == ".json") files.push_back(e.path());
    if (ec) return Error(ErrorCode::Io, fmt::format("cannot read {}: {}", dir, ec.message()));
    std::sort(files.begin(), files.end());
    for (const fs::path& p : files) {
        // The JSON reader throws (nlohmann's, and case_from's refusals): caught here, per file.
        try {
            if (fs::file_size(p) > kMaxEntryBytes) throw std::runtime_error("too large");
            std::ifstream in(p);
            out.push_back(case_from(json::parse(in)));
        } catch (const std::exception& e) {
            return Error(ErrorCode::InvalidInput, fmt::format("not a corpus entry: {}", e.what()),
                         p.string());
        }
    }
    return out;
}

}  // namespace mbstorm::netfuzz
