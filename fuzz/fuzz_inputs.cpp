// libFuzzer harness: what `mbstorm fuzz` reads from the user: a device map (`--map`) and a
// saved model (`--model`, model.json). The first byte picks which. A model it accepts
// survives a round trip through its own JSON.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "netfuzz/device_model.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size == 0) return 0;
    const std::string text(reinterpret_cast<const char*>(data + 1), size - 1);
    mbstorm::netfuzz::DeviceModel model, again;
    std::string error;
    const bool ok = data[0] & 1 ? mbstorm::netfuzz::parse_map(text, model, error)
                                : mbstorm::netfuzz::model_from_json(text, model, error);
    if (!ok) return 0;
    if (!mbstorm::netfuzz::model_from_json(mbstorm::netfuzz::model_to_json(model), again, error))
        std::abort();
    return 0;
}
