// Planted fault: wrong exception precedence. FC 03/04 check the address range (of a
// 4096-register table) before the quantity, so an invalid quantity at a high address gets
// 02 where v1.1b3 says 03 (quantity is checked first).
#include "broken_server_common.hpp"

namespace {
broken::Action address_before_quantity(const std::uint8_t* adu, std::size_t size,
                                       std::vector<std::uint8_t>& reply,
                                       mbstorm::slave::DataModel&) {
    if (size == 12 && (adu[7] == 0x03 || adu[7] == 0x04)) {
        const std::uint32_t address = mbstorm::codec::load_be16(adu + 8);
        const std::uint32_t quantity = mbstorm::codec::load_be16(adu + 10);
        if (address + quantity > 0x1000) {
            broken::exception_reply(adu, 0x02, reply);
            return broken::Action::Reply;
        }
    }
    return broken::Action::Default;
}
}  // namespace

int main(int argc, char** argv) {
    broken::Faults f;
    f.on_frame = address_before_quantity;
    return broken::main_with(argc, argv, f);
}
