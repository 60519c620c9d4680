// The four data tables of the Modbus data model.
#pragma once

#include <cstdint>

namespace mbstorm::codec {

enum class Table : std::uint8_t { Coils, DiscreteInputs, InputRegisters, HoldingRegisters };

}  // namespace mbstorm::codec
