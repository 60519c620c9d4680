// Field-by-field description of Modbus frames for `mbstorm decode`, laid out the way the
// seed documents tabulate frames: field name, the bytes on the wire, and their meaning.
#pragma once

#include <string>
#include <vector>

#include "codec/bytes.hpp"
#include "util/error.hpp"

namespace mbstorm::cli {

struct FieldRow {
    std::string field;
    std::string hex;
    std::string meaning;
};

enum class Direction { Request, Response };

// Rows for a PDU (function code first), appended to `rows` (with the bad field marked when
// the PDU does not decode in that direction: an InvalidInput error then says why).
Error describe_pdu(codec::Bytes pdu, Direction dir, std::vector<FieldRow>& rows);

// What is wrong with a request PDU, as one phrase naming the field, its value and the valid
// range ("quantity 200: valid 1..125 for 0x03 read_holding_registers"); "" when it is valid.
std::string request_fault(codec::Bytes pdu);

// "1 byte", "2 bytes".
std::string byte_count(std::size_t n);

// Renders rows as an aligned three-column table.
std::string render_rows(const std::vector<FieldRow>& rows);

}  // namespace mbstorm::cli
