// libFuzzer harness: a device description (`serve --device FILE`, a scenario's `slave:`) ->
// a DeviceDescription, or a DeviceYamlError naming the position.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "slave/device_yaml.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string_view text(reinterpret_cast<const char*>(data), size);
    try {
        (void)mbstorm::slave::parse_device_yaml(text);
    } catch (const mbstorm::slave::DeviceYamlError&) {
    }
    return 0;
}
