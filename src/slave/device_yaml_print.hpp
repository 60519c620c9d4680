// Device description -> YAML: every key of scenarios/devices/README.md written out, defaults
// included, in the syntax parse_device_node() accepts, so the text reads back to the same
// description. Used by `mbstorm run --print-scenario` for the embedded slave's `slave:` section.
#pragma once

#include <string>

#include "slave/device_yaml.hpp"

namespace YAML {
class Emitter;
}

namespace mbstorm::slave {

// Writes `device` as one YAML mapping at the emitter's current position (e.g. after a Value).
// Init data comes out as the 16-bit words it resolved to (`random:` and `float32` entries
// become plain `values:`). Interval counters (Waveform::Counter) are written under `counters:`,
// so they read back ahead of the other simulated inputs, which is where the parser puts them.
void emit_device_yaml(YAML::Emitter& out, const DeviceDescription& device);

// The same as a standalone document (newline-terminated).
std::string format_device_yaml(const DeviceDescription& device);

}  // namespace mbstorm::slave
