// Planted fault: FC 17 (read/write multiple registers) answers with the transaction id's top
// bit cleared, as a server storing it in a signed 16-bit field and masking would.
#include "broken_server_common.hpp"

namespace {
void clear_tid_top_bit(const std::uint8_t* request, std::vector<std::uint8_t>& reply) {
    if (request[7] == 0x17) reply[0] &= 0x7F;
}
}  // namespace

int main(int argc, char** argv) {
    broken::Faults f;
    f.on_reply = clear_tid_top_bit;
    return broken::main_with(argc, argv, f);
}
