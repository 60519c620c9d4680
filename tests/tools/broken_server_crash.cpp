// Planted fault: FC 0F (write multiple coils) with quantity 0 crashes the process, as a
// server computing (quantity - 1) / 8 + 1 bytes in an unsigned 16-bit type would.
#include "broken_server_common.hpp"

namespace {
broken::Action crash_on_zero_coils(const std::uint8_t* adu, std::size_t size,
                                   std::vector<std::uint8_t>&, mbstorm::slave::DataModel&) {
    if (size >= 12 && adu[7] == 0x0F && adu[10] == 0 && adu[11] == 0) std::abort();
    return broken::Action::Default;
}
}  // namespace

int main(int argc, char** argv) {
    broken::Faults f;
    f.on_frame = crash_on_zero_coils;
    return broken::main_with(argc, argv, f);
}
