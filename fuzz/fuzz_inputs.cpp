// libFuzzer harness: what `mbstorm fuzz` reads from the user: a device map (`--map`) and a
// saved model (`--model`, model.json). The first byte picks which. A model it accepts
// survives a round trip through its own JSON unchanged: every table's ranges, largest
// quantity and write behaviour, the units and the exception pauses, and the JSON printed
// again is the same text. model_from_json reads neither `source` nor `partial` (the reader
// names the source itself; a partial model loses its mark: left to src/netfuzz), so those two
// are carried over before the texts are compared.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "netfuzz/device_model.hpp"

namespace {

using mbstorm::netfuzz::DeviceModel;

bool same(const DeviceModel& a, const DeviceModel& b) {
    for (std::size_t t = 0; t < a.tables.size(); ++t) {
        const auto &x = a.tables[t], &y = b.tables[t];
        if (x.ranges != y.ranges || x.max_quantity != y.max_quantity || x.writes != y.writes)
            return false;
    }
    return a.units == b.units && a.exception_pause_ms == b.exception_pause_ms;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size == 0) return 0;
    const std::string text(reinterpret_cast<const char*>(data + 1), size - 1);
    const mbstorm::Result<DeviceModel> parsed =
        data[0] & 1 ? mbstorm::netfuzz::parse_map(text) : mbstorm::netfuzz::model_from_json(text);
    if (!parsed.ok()) return 0;
    const DeviceModel& model = *parsed;
    const std::string json = mbstorm::netfuzz::model_to_json(model);
    mbstorm::Result<DeviceModel> read_back = mbstorm::netfuzz::model_from_json(json);
    if (!read_back.ok() || !same(model, *read_back)) std::abort();
    DeviceModel& again = *read_back;
    again.source = model.source;
    again.partial = model.partial;
    if (mbstorm::netfuzz::model_to_json(again) != json) std::abort();
    return 0;
}
