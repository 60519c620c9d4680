// Field-level minimisation: a request that is wrong in several fields, each made right but one,
// so that a finding is named after the check the target really skips. A request whose value
// is invalid and whose address lies outside the map gets 02 from a server that never checks
// the value (the address check is the only one it has); with the address moved into the map
// the same server answers it normally, which is the defect.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "codec/bytes.hpp"
#include "netfuzz/device_model.hpp"

namespace mbstorm::netfuzz {

// The request PDU `pdu` with every address field it has (FC 17: both) moved to the first
// address of a range of the model's table for its function code, the rest unchanged.
// Nothing when the function takes no address, the PDU is too short to hold one, the model
// knows no range of that table, or every address is in the map already.
std::optional<std::vector<std::uint8_t>> with_addresses_in_map(codec::Bytes pdu,
                                                               const DeviceModel& model);

}  // namespace mbstorm::netfuzz
