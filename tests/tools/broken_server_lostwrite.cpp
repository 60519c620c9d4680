// Planted fault: FC 10 (write multiple registers) stores only the first 16 registers but
// acknowledges all of them; only a read after the write shows it.
#include "broken_server_common.hpp"

namespace {
broken::Action truncate_long_writes(const std::uint8_t* adu, std::size_t size,
                                    std::vector<std::uint8_t>& reply,
                                    mbstorm::slave::DataModel& model) {
    if (size < 13 || adu[7] != 0x10) return broken::Action::Default;
    const std::uint16_t address = mbstorm::codec::load_be16(adu + 8);
    const std::uint16_t quantity = mbstorm::codec::load_be16(adu + 10);
    if (quantity <= 16 || quantity > 123 || adu[12] != 2 * quantity || size != 13u + 2 * quantity ||
        address + quantity > 0x10000)
        return broken::Action::Default;
    model.holding_registers().write_be(address, 16, adu + 13);
    reply.assign(adu, adu + 12);
    mbstorm::codec::store_be16(reply.data() + 4, 6);
    return broken::Action::Reply;
}
}  // namespace

int main(int argc, char** argv) {
    broken::Faults f;
    f.on_frame = truncate_long_writes;
    return broken::main_with(argc, argv, f);
}
