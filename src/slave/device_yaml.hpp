// Device description from YAML: table sizes, shared or per-unit models, initial data, counters,
// simulated inputs, identification and fault settings. Every key is documented in
// scenarios/devices/README.md. Not on the hot path. The loaders return an Error whose message
// starts with "<source>:<line>:<column>: "; only parse_device_node, for YAML parsers that embed
// a device, throws (DeviceYamlError), inside its caller's own exception-based parsing.
#pragma once

#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "codec/function_set.hpp"
#include "slave/data_model.hpp"
#include "slave/faults.hpp"
#include "slave/simulator.hpp"
#include "util/error.hpp"
#include "yaml/positioned_error.hpp"

namespace YAML {
class Node;
}

namespace mbstorm::slave {

class DeviceYamlError : public yaml::PositionedError {
  public:
    using PositionedError::PositionedError;
};

// Initial contents: `words` (registers, or 0/1 for bit tables) stored from `address` on.
struct InitRange {
    Table table = Table::HoldingRegisters;
    std::uint16_t address = 0;
    std::vector<std::uint16_t> words;
    std::vector<std::uint8_t> units;  // empty: every model
    bool operator==(const InitRange&) const = default;
};

// A register that grows by `step` before each read that covers it.
struct ReadCounterSpec {
    Table table = Table::InputRegisters;  // input or holding registers
    std::uint16_t address = 0;
    std::uint16_t step = 1;
    std::uint16_t start = 0;
    std::vector<std::uint8_t> units;
    bool operator==(const ReadCounterSpec&) const = default;
};

struct DeviceDescription {
    ModelConfig model;
    bool shared = true;               // one model for every unit id
    std::vector<std::uint8_t> units;  // per-unit mode: the unit ids served
    UnknownUnitPolicy unknown_unit = UnknownUnitPolicy::GatewayTargetFailed;
    bool broadcast_unit_zero = false;
    std::vector<InitRange> init;
    std::vector<ReadCounterSpec> read_counters;
    std::vector<SimulatedInput> simulated;  // includes interval counters (Waveform::Counter)
    FaultConfig faults;
    // Modbus/TCP Security: the function codes each client role may use (`tls_roles:`, the
    // same lists as serve --tls-role); applied when the device is served over TLS.
    std::vector<std::pair<std::string, codec::FunctionSet>> tls_roles;
    // Member by member: a description printed and read back must be the one printed.
    bool operator==(const DeviceDescription&) const = default;
};

// The YAML keys of the named identification objects (`identification:`), in object-id order.
struct IdentificationKey {
    const char* key;
    std::uint8_t object_id;
};
std::span<const IdentificationKey> identification_keys() noexcept;

// InvalidInput naming the place ("dev.yaml:3:5: unknown key ...") when the text is not a
// device description; load_device_file's is Io when the file cannot be read.
Result<DeviceDescription> parse_device_yaml(std::string_view text,
                                            std::string_view source = "<device>");
Result<DeviceDescription> load_device_file(const std::string& path);
// For documents that embed a device description (e.g. a scenario's `slave:` section): throws
// DeviceYamlError (with its line and column), which the embedding parser turns into its own
// error, as scenario parsing does at its edge.
DeviceDescription parse_device_node(const YAML::Node& node, std::string_view source);

// Builds the models and applies initial data and read counters.
UnitModels build_units(const DeviceDescription& device);

}  // namespace mbstorm::slave
