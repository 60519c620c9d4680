// libFuzzer harness: a device description (`serve --device FILE`, a scenario's `slave:`) ->
// a DeviceDescription, or an Error naming the position. A description it accepts
// prints (format_device_yaml, what run --print-scenario writes under `slave:`) as YAML that
// parses to the same description (every member equal), which prints the same again. Any
// other exception, or a sanitizer report, is a bug.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>

#include "slave/device_yaml.hpp"
#include "slave/device_yaml_print.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    using namespace mbstorm::slave;
    const std::string_view text(reinterpret_cast<const char*>(data), size);
    const mbstorm::Result<DeviceDescription> device = parse_device_yaml(text);
    if (!device.ok()) return 0;
    const std::string printed = format_device_yaml(*device);
    const mbstorm::Result<DeviceDescription> again = parse_device_yaml(printed);
    if (!again.ok()) std::abort();  // what it printed, it must read back
    if (!(*again == *device) || format_device_yaml(*again) != printed) std::abort();
    return 0;
}
