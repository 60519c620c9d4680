// The one place that names root-cause rules (issue #26): every rule text the fuzzer writes
// into a Verdict, or compares one with, comes from here. A rule, with its oracle, is a
// finding's identity, and saved finding.json files and tests compare the texts byte for byte:
// never reword one. A rule is a stem, optionally followed by "(detail)" and/or "/culprit"
// (rule_stem and culprit_of cut them); the functions below put the parts together.
// tests/scripts/one_place_per_fact.sh fails when a .cpp under src/netfuzz spells one of the
// hyphenated texts below as a literal instead of naming it.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

namespace mbstorm::netfuzz {

// ---- The target as a whole (the fresh probe, the sentinels, the process watch) ----

// A fresh connection is refused or closed, or the process died or restarted: a crash.
inline constexpr const char* kTargetDownRule = "target-down";
// A fresh connection is accepted but its probe gets no (or a bad) answer.
inline constexpr const char* kWholeServerHangRule = "whole-server-hang";
// While one connection held something, a concurrent connection was answered late or not at
// all ("stalls-other-connections(partial-frame)").
inline constexpr const char* kStallsOtherConnectionsRule = "stalls-other-connections";
// The capacity check, or a flood, found connections accepted and then left unanswered.
inline constexpr const char* kCapacityUnservedRule = "capacity/accepted-connections-unserved";
// The capacity check: the oldest connection stopped answering as more were opened.
inline constexpr const char* kCapacityExistingUnservedRule =
    "capacity/existing-connections-unserved";

// ---- Silence or a close on one connection (executor.cpp silence_rule) ----

// A request (the culprit) drew no answer while the connection stayed open.
inline constexpr const char* kNoAnswerRule = "no-answer";
// The connection closed with a request (the culprit) unanswered.
inline constexpr const char* kCloseWithRequestPendingRule = "close-with-request-pending";
// The requests after the culprit's request went unanswered on an open connection.
inline constexpr const char* kDropsRequestsAfterRule = "drops-requests-after";
// The connection closed after answering the culprit's request, with later ones pending.
inline constexpr const char* kClosesAfterRule = "closes-after";
// Requests pipelined behind one answered with an exception went unanswered (libmodbus
// flushes its socket after an exception).
inline constexpr const char* kDropsRequestsAfterExceptionRule = "drops-requests-after-exception";
// The connection closed after answering a request with an exception, with later ones pending.
inline constexpr const char* kClosesAfterExceptionRule = "closes-after-exception";
// Complete requests sent before our half-close went unanswered.
inline constexpr const char* kDropsAnswersOnHalfCloseRule = "drops-answers-on-half-close";
// A server that closes the connection on a request it cannot use (whatever its function code):
// one policy of its framing.
inline constexpr const char* kClosesOnInvalidRequestRule =
    "close-with-request-pending/invalid-request";
// A request whose PDU length disagrees with its function code (oracle.hpp
// pdu_length_mismatch) lost the stream: a close, silence or a stray answer after it.
inline constexpr const char* kStreamLostRule = "stream-lost-after-pdu-length-mismatch";
// The same valid request sent again and again (MutationClass::Repeated) went unanswered
// once: the target drops requests at random.
inline constexpr const char* kRandomDropRule = "drops-requests-at-random";
// The same, but the connection closed under it.
inline constexpr const char* kRandomCloseRule = "closes-at-random";

// ---- Frames delivered in pieces ----

// A frame delivered in pieces that the target acted on before it was whole: an answer to a
// started frame alone, or a close or silence with the split request unanswered. However it
// shows, it is the target's reassembly: one root cause (finding.cpp keys the family as one).
inline constexpr const char* kAnswersPartialFrameRule = "answers-partial-frame";
// The key (not a rule) that family shares in root_cause_key.
inline constexpr const char* kPartialFrameFamily = "mishandles-partial-frame";
// The same family when the target closed the connection as soon as it read the first piece.
inline constexpr const char* kClosesOnPartialFrameRule = "closes-on-partial-frame";

// ---- Malformed responses ----

// An answer whose transaction id matches no request sent on its connection.
inline constexpr const char* kUnmatchedTransactionIdRule = "unmatched-transaction-id";
// RTU/ASCII: an answer whose CRC or LRC is wrong.
inline constexpr const char* kResponseCheckFailedRule = "response-check-failed";
// No frame can start where the answers went on (a bad MBAP length, or RTU/ASCII garbage).
inline constexpr const char* kResponseFramingRule = "response-framing";
// An answer with a protocol id other than 0.
inline constexpr const char* kResponseProtocolIdRule = "response-protocol-id";
// An answer from another unit id than the request's.
inline constexpr const char* kResponseUnitIdRule = "response-unit-id";
// An answer whose function code is neither the request's nor its exception form.
inline constexpr const char* kResponseFunctionRule = "response-function";
// An exception answer that is not exactly function + code.
inline constexpr const char* kExceptionResponseLengthRule = "exception-response-length";
// A read answered with more or fewer data bytes than its quantity needs.
inline constexpr const char* kReadDataSizeRule = "read-data-size";
// A write's answer does not echo its address, value, quantity or masks.
inline constexpr const char* kEchoDiffersRule = "echo-differs";
// FC 08: the answer's sub-function is not the request's.
inline constexpr const char* kSubFunctionNotEchoedRule = "sub-function-not-echoed";
// FC 08 return-query-data: the data is not echoed.
inline constexpr const char* kQueryDataNotEchoedRule = "query-data-not-echoed";
// FC 2B: the answer's MEI type is not the request's.
inline constexpr const char* kMeiTypeNotEchoedRule = "mei-type-not-echoed";

// ---- Spec deviations ----

// A frame with a protocol id other than 0 (or a TLS record's bytes) was answered.
inline constexpr const char* kAnswersNonzeroProtocolIdRule = "answers-nonzero-protocol-id";
// An unknown sub-function (FC 08) or MEI type (FC 2B) answered other than with exception 01:
// one missing check however it is answered.
inline constexpr const char* kSubFunctionNot01Rule = "unknown-sub-function-not-refused-with-01";
// A request the codec owes an exception answered normally ("...(owes-03)/fc0F").
inline constexpr const char* kInvalidAnsweredNormallyRule = "invalid-request-answered-normally";
// A read of what a write just stored shows another value ("...(coils)/fc0F").
inline constexpr const char* kReadAfterWriteMismatchRule = "read-after-write-mismatch";
// The TLS port served plain Modbus/TCP: a client without a certificate is served.
inline constexpr const char* kTlsPortAnswersPlaintextRule = "tls-port-answers-plaintext";
// Plain Modbus/TCP between the records of a TLS session was answered.
inline constexpr const char* kTlsSessionAnswersPlaintextRule = "tls-session-answers-plaintext";

// ---- Culprits: the "/..." part naming what a fault is blamed on ----

// A frame delivered in pieces (split, burst-split, partial-hold, drip): the target's
// reassembly, whatever was asked. Also what a stalled concurrent connection was held by.
inline constexpr const char* kPartialFrameCulprit = "partial-frame";
// A function code the codec does not know: one default branch, whatever the code.
inline constexpr const char* kUnknownFunctionCulprit = "unknown-fc";
// The capacity check (capacity.cpp), not any one request.
inline constexpr const char* kCapacityCulprit = "capacity";
// A whole pipelined batch, lost at once.
inline constexpr const char* kPipelinedBatchCulprit = "pipelined-batch";
// What else a stalled concurrent connection waited behind ("stalls-other-connections(...)").
inline constexpr const char* kExceptionHeld = "exception";
inline constexpr const char* kRequestHeld = "request";
// A handler's culprit starts so ("fc0F"; culprit.cpp tells handlers from classes by it).
inline constexpr const char* kFunctionCulpritPrefix = "fc";

// "fc0F": the handler of one function code.
std::string function_culprit(std::uint8_t function);
// "stem/culprit": a rule blamed on a request, a class or the capacity check.
std::string rule_with_culprit(std::string_view stem, std::string_view culprit);
// "target-down/fc0F": the target went down after the culprit.
std::string target_down_rule(std::string_view culprit);
// "stalls-other-connections(partial-frame)": what the stalling connection held.
std::string stalls_other_connections_rule(std::string_view held);
// The silence rules, closed or open: "close-with-request-pending/fc0F" or "no-answer/fc0F".
std::string unanswered_rule(bool closed, std::string_view culprit);
// "closes-after/fc0F" or "drops-requests-after/fc0F": the requests after the culprit's lost.
std::string after_request_rule(bool closed, std::string_view culprit);
// kClosesAfterExceptionRule or kDropsRequestsAfterExceptionRule.
const char* after_exception_rule(bool closed);
// "answers-bad-crc": an RTU/ASCII frame a conforming reader discards (why) was answered.
std::string answers_discarded_rule(std::string_view why);
// "exception-03-to-valid-request": an exception no valid request can owe.
std::string exception_to_valid_request_rule(std::uint8_t answered);
// "exception-02-where-03-owed": the wrong exception (one wrong check order).
std::string exception_where_owed_rule(std::uint8_t answered, std::uint8_t owed);
// "exception-02-where-": what every exception_where_owed_rule(answered, ...) starts with.
std::string exception_where_owed_prefix(std::uint8_t answered);
// "invalid-request-answered-normally(owes-03)/fc0F": the handler skips the check owing it.
std::string invalid_answered_normally_rule(std::uint8_t owed, std::uint8_t function);
// "unmapped-address-answered-normally(holding_registers)" (codec::table_name, with
// underscores, unlike read_after_write_rule's table): a read over an address the
// device refused alone was answered normally.
std::string unmapped_address_rule(std::string_view table);
// "undecodable-response(byte_count_mismatch)": a normal answer the codec cannot decode.
std::string undecodable_response_rule(std::string_view codec_error);
// "read-after-write-mismatch-other-connection(coils)/fc0F": the writer's function ends it.
std::string read_after_write_rule(bool other_connection, std::string_view table,
                                  std::uint8_t writer);
// The same mismatch read back on the writer's own connection: "read-after-write-mismatch(coils)
// /fc0F" for "read-after-write-mismatch-other-connection(coils)/fc0F"; "" for any other rule.
std::string same_connection_rule(std::string_view rule);

}  // namespace mbstorm::netfuzz
