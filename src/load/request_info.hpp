// What a transaction remembers about its request so that the response can be checked.
#pragma once

#include <cstdint>

namespace mbstorm::load {

struct RequestInfo {
    std::uint16_t op_index = 0;  // index into Plan::operations
    std::uint8_t function = 0;
    std::uint8_t unit_id = 0;
    std::uint16_t address = 0;       // start address (FC18: FIFO pointer)
    std::uint16_t quantity = 0;      // items read (FC01-04, 17) or written (FC0F, 10)
    std::uint16_t value = 0;         // FC05 (0xFF00/0), FC06 value, FC16 OR mask
    std::uint16_t and_mask = 0;      // FC16
    std::uint16_t sub_function = 0;  // FC08
    // FC01-04: the byte count of the answer that carries exactly what was asked for, which
    // is_expected_read_answer() accepts in a few compares; 0 for every other function.
    std::uint8_t answer_bytes = 0;
};

}  // namespace mbstorm::load
