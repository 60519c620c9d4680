// A finding: what went wrong, the case that does it, and the exact traffic per connection.
// Saved as one folder (finding.json, summary.txt, traffic.txt); loaded back by `replay`.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "netfuzz/case.hpp"
#include "netfuzz/executor.hpp"
#include "netfuzz/oracle.hpp"
#include "util/error.hpp"

namespace mbstorm::netfuzz {

// A finding's root-cause identity: the oracle and the rule its verdict violates.
std::string root_cause_key(const Verdict& v);

// The part of a rule a smaller or replayed case must keep: all of it but the detail that
// names the request (a codec reason in brackets, a culprit after '/').
std::string rule_stem(const std::string& rule);

// The same fault: the same oracle and rule stem (what minimisation and replay ask for).
bool same_fault(const Verdict& a, const Verdict& b);

// Whether --baseline knew a finding's root cause (None: no baseline given).
enum class BaselineState : std::uint8_t { None, New, Known };

struct Finding {
    std::size_t id = 0;
    Verdict verdict;
    Case fuzz_case;      // the reproducer (minimised when `minimized`)
    Case original_case;  // the case as it first fired, always kept
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
    // Every case that showed this root cause: how many, and under which function code, class
    // and unit id ("fc03 invalid-values unit 1" -> count).
    std::uint64_t hits = 1;
    std::map<std::string, std::uint64_t> variants;
    std::string minimize_note;  // why it was not (fully) minimised, if it was not
    // The fields of the culprit request still wrong in the reproducer once field repair made
    // the others right ("byte-count", "address": field_repair.hpp); empty when none or unknown.
    std::vector<std::string> wrong_fields;
    unsigned restarts = 0;  // target restarts this root cause cost (finding, confirming,
                            // minimising it)
    int timeout_ms = 1000;
    // Where its run checked reads after writes: replay checks the same range.
    StateRange state;
    std::string folder;  // where it was saved ("" if not saved)
    BaselineState baseline = BaselineState::None;

    Oracle oracle() const noexcept { return verdict.oracle; }
    // Root-cause key: "crash:target-down/fc0F-invalid".
    std::string key() const { return root_cause_key(verdict); }
    // The function code of the culprit request, if the fault has one.
    int function() const noexcept { return verdict.culprit_fc; }
};

// Writes `dir`/finding.json, summary.txt and traffic.txt; an Io error when it cannot.
Error save_finding(const Finding& f, const std::string& dir);
// Accepts the folder or the finding.json path. NotFound when there is no such file; a file
// that is not a finding is an InvalidInput error placed at its path.
Result<Finding> load_finding(const std::string& path);

std::string to_hex(const std::vector<std::uint8_t>& bytes);
bool from_hex(const std::string& text, std::vector<std::uint8_t>& out);

}  // namespace mbstorm::netfuzz
