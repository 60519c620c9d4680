#include "netfuzz/rules.hpp"

#include <fmt/format.h>

namespace mbstorm::netfuzz {

std::string function_culprit(std::uint8_t function) {
    return fmt::format("{}{:02X}", kFunctionCulpritPrefix, function);
}

std::string rule_with_culprit(std::string_view stem, std::string_view culprit) {
    return fmt::format("{}/{}", stem, culprit);
}

std::string target_down_rule(std::string_view culprit) {
    return rule_with_culprit(kTargetDownRule, culprit);
}

std::string stalls_other_connections_rule(std::string_view held) {
    return fmt::format("{}({})", kStallsOtherConnectionsRule, held);
}

std::string unanswered_rule(bool closed, std::string_view culprit) {
    return rule_with_culprit(closed ? kCloseWithRequestPendingRule : kNoAnswerRule, culprit);
}

std::string after_request_rule(bool closed, std::string_view culprit) {
    return rule_with_culprit(closed ? kClosesAfterRule : kDropsRequestsAfterRule, culprit);
}

const char* after_exception_rule(bool closed) {
    return closed ? kClosesAfterExceptionRule : kDropsRequestsAfterExceptionRule;
}

std::string answers_discarded_rule(std::string_view why) {
    return fmt::format("answers-{}", why);
}

std::string exception_to_valid_request_rule(std::uint8_t answered) {
    return fmt::format("exception-{:02X}-to-valid-request", answered);
}

std::string exception_where_owed_rule(std::uint8_t answered, std::uint8_t owed) {
    return fmt::format("{}{:02X}-owed", exception_where_owed_prefix(answered), owed);
}

std::string exception_where_owed_prefix(std::uint8_t answered) {
    return fmt::format("exception-{:02X}-where-", answered);
}

std::string invalid_answered_normally_rule(std::uint8_t owed, std::uint8_t function) {
    return fmt::format("{}(owes-{:02X})/{}", kInvalidAnsweredNormallyRule, owed,
                       function_culprit(function));
}

std::string unmapped_address_rule(std::string_view table) {
    return fmt::format("unmapped-address-answered-normally({})", table);
}

std::string undecodable_response_rule(std::string_view codec_error) {
    return fmt::format("undecodable-response({})", codec_error);
}

std::string same_connection_rule(std::string_view rule) {
    const std::string_view stem = kReadAfterWriteMismatchRule;
    constexpr std::string_view kOther = "-other-connection";
    if (rule.substr(0, stem.size()) != stem || rule.substr(stem.size(), kOther.size()) != kOther)
        return {};
    std::string out(stem);
    out.append(rule.substr(stem.size() + kOther.size()));
    return out;
}

std::string read_after_write_rule(bool other_connection, std::string_view table,
                                  std::uint8_t writer) {
    return fmt::format("{}{}({})/{}", kReadAfterWriteMismatchRule,
                       other_connection ? "-other-connection" : "", table,
                       function_culprit(writer));
}

}  // namespace mbstorm::netfuzz
