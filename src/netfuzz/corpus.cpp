#include "netfuzz/corpus.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "netfuzz/finding.hpp"

namespace mbstorm::netfuzz {
namespace {

using nlohmann::json;
namespace fs = std::filesystem;

constexpr std::size_t kMaxSteps = 4096;
constexpr std::size_t kMaxEntryBytes = 1 << 20;

// A whole number in [0, max] from `j[key]` (absent: 0); throws otherwise.
std::uint64_t bounded_number(const json& j, const char* key, std::uint64_t max) {
    if (!j.contains(key)) return 0;
    const json& v = j.at(key);
    if (!v.is_number_unsigned() || v.get<std::uint64_t>() > max)
        throw std::runtime_error(fmt::format("'{}' is not a whole number from 0 to {}", key, max));
    return v.get<std::uint64_t>();
}

Case case_from(const json& j) {
    Case c;
    if (!class_from_name(j.at("class").get<std::string>(), c.cls))
        throw std::runtime_error("unknown class");
    c.function = static_cast<std::uint8_t>(bounded_number(j, "function", 255));
    for (const json& s : j.at("steps")) {
        Step st;
        if (!op_from_name(s.at("op").get<std::string>(), st.op))
            throw std::runtime_error("unknown step op");
        st.conn = static_cast<std::uint8_t>(bounded_number(s, "conn", 7));
        st.delay_us = static_cast<std::uint32_t>(bounded_number(s, "delay_us", 60'000'000));
        st.count = static_cast<std::uint16_t>(bounded_number(s, "count", 4096));
        if (!from_hex(s.value("hex", ""), st.bytes)) throw std::runtime_error("bad hex");
        c.steps.push_back(std::move(st));
        if (c.steps.size() > kMaxSteps) throw std::runtime_error("too many steps");
    }
    if (c.steps.empty()) throw std::runtime_error("no steps");
    return c;
}

}  // namespace

bool save_corpus_entry(const std::string& dir, std::size_t index, const Case& c,
                       std::string& error) {
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec) {
        error = fmt::format("cannot create {}: {}", dir, ec.message());
        return false;
    }
    json steps = json::array();
    for (const Step& s : c.steps)
        steps.push_back({{"op", op_name(s.op)},
                         {"conn", s.conn},
                         {"delay_us", s.delay_us},
                         {"count", s.count},
                         {"hex", to_hex(s.bytes)}});
    const json j = {{"class", class_name(c.cls)}, {"function", c.function}, {"steps", steps}};
    const std::string path = fmt::format("{}/{:06}.json", dir, index);
    std::ofstream out(path);
    out << j.dump(1) << "\n";
    if (!out) {
        error = fmt::format("cannot write {}", path);
        return false;
    }
    return true;
}

bool load_corpus(const std::string& dir, std::vector<Case>& out, std::string& error) {
    std::error_code ec;
    if (!fs::exists(dir, ec)) return true;
    std::vector<fs::path> files;
    for (const auto& e : fs::directory_iterator(dir, ec))
        if (e.path().extension() == ".json") files.push_back(e.path());
    if (ec) {
        error = fmt::format("cannot read {}: {}", dir, ec.message());
        return false;
    }
    std::sort(files.begin(), files.end());
    for (const fs::path& p : files) {
        try {
            if (fs::file_size(p) > kMaxEntryBytes) throw std::runtime_error("too large");
            std::ifstream in(p);
            out.push_back(case_from(json::parse(in)));
        } catch (const std::exception& e) {
            error = fmt::format("{}: not a corpus entry: {}", p.string(), e.what());
            return false;
        }
    }
    return true;
}

}  // namespace mbstorm::netfuzz
