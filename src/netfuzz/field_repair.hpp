// Field-level minimisation: a request that is wrong in several fields, each made right but one,
// so that a finding is named after the check the target really skips. A request whose value
// is invalid and whose address lies outside the map gets 02 from a server that never checks
// the value (the address check is the only one it has); with the address moved into the map
// the same server answers it normally, which is the defect.
#pragma once

#include <cstdint>
#include <optional>
#include <string_view>
#include <vector>

#include "codec/bytes.hpp"
#include "codec/framing.hpp"
#include "netfuzz/case.hpp"
#include "netfuzz/device_model.hpp"
#include "netfuzz/executor.hpp"

namespace mbstorm::netfuzz {

// The request PDU `pdu` with every address field it has (FC 17: both) moved to the first
// address of a range of the model's table for its function code, the rest unchanged.
// Nothing when the function takes no address, the PDU is too short to hold one, the model
// knows no range of that table, or every address is in the map already.
std::optional<std::vector<std::uint8_t>> with_addresses_in_map(codec::Bytes pdu,
                                                               const DeviceModel& model);

// A field of a request that a server checks before it acts on it: the counts, the byte count
// and the data it announces, a single coil's value (exception 03 in v1.1b3's flow), then the
// address ranges (02). FC 17 has two of each count and range: read, then write.
enum class RequestField : std::uint8_t {
    Quantity,
    WriteQuantity,
    ByteCount,
    DataLength,
    Value,
    Address,
    WriteAddress,
};
// As finding.json and the summary name it: "byte-count", "write-address", ...
std::string_view field_name(RequestField field) noexcept;

// The fields of request PDU `pdu` that are wrong, in the order above: a count outside its
// function's limits, a byte count that disagrees with its count, data that disagrees with the
// byte count, FC 05's value, and (when the model knows the table) a range outside the map.
// A range is judged with its count when the count is valid, else as one item.
std::vector<RequestField> wrong_fields(codec::Bytes pdu, const DeviceModel& model);

// Whether wrong count `field` (quantity, write quantity, byte count, data length) is too large
// (1) or too small (-1): a device checks each bound apart. 0 for any other field, or a right one.
int wrong_count_side(codec::Bytes pdu, RequestField field, const DeviceModel& model);

// `pdu` with `field` made right and nothing else changed (the data is cut or padded with zero
// bytes to its byte count; a count is made to agree with the byte count where that is valid,
// else 1); nothing when that field is right already or cannot be made right.
std::optional<std::vector<std::uint8_t>> with_field_repaired(codec::Bytes pdu, RequestField field,
                                                             const DeviceModel& model);

// A request of function `fc` the codec owes no exception and whose every address lies in one
// range of the model's map (the model's first range when it knows the table); nothing when
// no such request can be made (an unknown code, a table the model holds nothing of).
std::optional<std::vector<std::uint8_t>> valid_request_in_map(std::uint8_t fc,
                                                              const DeviceModel& model);

// The one request frame a send step holds (any framing), as its MBAP view; nothing when the
// step is not exactly one whole frame of function `fc` that a reader would take.
std::optional<std::vector<std::uint8_t>> step_request(const Step& s, int fc,
                                                      codec::Framing framing);
// The step's frame replaced with `mbap` in the step's framing.
void set_step_request(Step& s, const std::vector<std::uint8_t>& mbap, codec::Framing framing);

// Every byte the target sent on the case's own connections (not the fresh probe's), in order.
std::vector<std::uint8_t> answered_bytes(const std::vector<TraceEvent>& trace);

}  // namespace mbstorm::netfuzz
