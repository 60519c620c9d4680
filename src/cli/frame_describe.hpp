// Field-by-field description of Modbus frames for `mbstorm decode`, laid out the way the
// seed documents tabulate frames: field name, the bytes on the wire, and their meaning.
#pragma once

#include <string>
#include <vector>

#include "codec/bytes.hpp"

namespace mbstorm::cli {

struct FieldRow {
    std::string field;
    std::string hex;
    std::string meaning;
};

enum class Direction { Request, Response };

// Rows for a PDU (function code first). Returns false with `error` set when the PDU does not
// decode in that direction.
bool describe_pdu(codec::Bytes pdu, Direction dir, std::vector<FieldRow>& rows, std::string& error);

// Renders rows as an aligned three-column table.
std::string render_rows(const std::vector<FieldRow>& rows);

}  // namespace mbstorm::cli
