// Refuse to change a real device by accident: write function codes (05, 06, 08, 0F, 10, 15,
// 16, 17) go to a target outside the loopback range only when the user said allow_writes.
// Pure functions: the CLI and the scenario layer call them before anything is sent.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "load/plan.hpp"
#include "util/error.hpp"

namespace mbstorm::load {

// True for 127.0.0.0/8, ::1 and IPv4-mapped ::ffff:127.x.x.x. `address` must be numeric;
// anything else (a host name, garbage) is not loopback, so the check fails safe.
bool is_loopback_address(std::string_view address) noexcept;

struct WriteSafetyVerdict {
    std::vector<std::string> write_operations;  // "name (0x10 write_multiple_registers)"
    Error refusal;                              // Refused, saying why; none when allowed
    bool allowed() const noexcept { return refusal.ok(); }
};

// `resolved_address`: the numeric address the engine will connect to.
WriteSafetyVerdict check_write_safety(const std::vector<Operation>& operations,
                                      std::string_view resolved_address, bool allow_writes);

inline WriteSafetyVerdict check_write_safety(const Plan& plan, std::string_view resolved_address) {
    return check_write_safety(plan.operations, resolved_address, plan.allow_writes);
}

}  // namespace mbstorm::load
