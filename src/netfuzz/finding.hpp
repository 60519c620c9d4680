// A finding: what went wrong, the case that does it, and the exact traffic per connection.
// Saved as one folder (finding.json, summary.txt, traffic.txt); loaded back by `replay`.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "netfuzz/case.hpp"
#include "netfuzz/executor.hpp"
#include "netfuzz/oracle.hpp"

namespace mbstorm::netfuzz {

struct Finding {
    std::size_t id = 0;
    Verdict verdict;
    Case fuzz_case;
    std::vector<TraceEvent> trace;
    TargetProfile profile;
    std::string target;
    std::uint64_t seed = 0;
    std::uint64_t case_number = 0;  // cases run before it was found
    double found_after_s = 0;
    bool minimized = false;
    // False when no isolated run confirmed it (the target was lost before the case that did it
    // could be re-run alone); `note` then says why and what the reproducer holds.
    bool confirmed = true;
    std::string note;
    std::size_t original_steps = 0;
    int timeout_ms = 1000;
    std::string folder;  // where it was saved ("" if not saved)

    Oracle oracle() const noexcept { return verdict.oracle; }
    // Dedup key text: "crash/fc0F/invalid-values".
    std::string key() const;
};

// Writes `dir`/finding.json, summary.txt and traffic.txt. False with `error` on failure.
bool save_finding(const Finding& f, const std::string& dir, std::string& error);
// Accepts the folder or the finding.json path.
bool load_finding(const std::string& path, Finding& out, std::string& error);

std::string to_hex(const std::vector<std::uint8_t>& bytes);
bool from_hex(const std::string& text, std::vector<std::uint8_t>& out);

}  // namespace mbstorm::netfuzz
