#include "scenario/operation_names.hpp"

#include <fmt/format.h>

namespace mbstorm::scenario {

std::string OperationNames::add_default(const std::string& base) {
    // Names only ever join the set, so a suffix found taken once stays taken: resume after it.
    int& k = next_suffix_.try_emplace(base, 1).first->second;
    std::string name = base;
    for (;;) {
        if (k >= 2) name = fmt::format("{}_{}", base, k);
        ++probes_;
        ++k;
        if (names_.insert(name).second) return name;
    }
}

}  // namespace mbstorm::scenario
