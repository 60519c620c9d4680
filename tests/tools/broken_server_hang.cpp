// Planted fault: FC 2B/0E (read device identification) asking for one specific object in the
// extended range (code 04, object id >= 0x80) makes the server stop serving that connection,
// as a loop over a missing object list would. Other connections are still served.
#include "broken_server_common.hpp"

namespace {
broken::Action hang_on_extended_object(const std::uint8_t* adu, std::size_t size,
                                       std::vector<std::uint8_t>&, mbstorm::slave::DataModel&) {
    if (size >= 11 && adu[7] == 0x2B && adu[8] == 0x0E && adu[9] == 0x04 && adu[10] >= 0x80)
        return broken::Action::StopServing;
    return broken::Action::Default;
}
}  // namespace

int main(int argc, char** argv) {
    broken::Faults f;
    f.on_frame = hang_on_extended_object;
    return broken::main_with(argc, argv, f);
}
