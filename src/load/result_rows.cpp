#include "load/result_rows.hpp"

#include <string>

#include "codec/function_code.hpp"

namespace mbstorm::load {

std::vector<stats::OperationResult> operation_rows(const std::vector<Operation>& operations) {
    std::vector<stats::OperationResult> rows;
    rows.reserve(operations.size());
    for (const Operation& op : operations) {
        stats::OperationResult r;
        r.name = op.name.empty() ? std::string(codec::function_name(op.function)) : op.name;
        r.function_code = op.function;
        rows.push_back(std::move(r));
    }
    return rows;
}

std::vector<stats::StageResult> stage_rows(std::size_t stages,
                                           const std::vector<stats::OperationResult>& operations) {
    std::vector<stats::StageResult> rows(stages);
    if (operations.size() <= 1) return rows;
    for (auto& stage : rows) {
        for (const auto& op : operations) {
            stats::OperationResult r;
            r.name = op.name;
            r.function_code = op.function_code;
            stage.operations.push_back(std::move(r));
        }
    }
    return rows;
}

}  // namespace mbstorm::load
