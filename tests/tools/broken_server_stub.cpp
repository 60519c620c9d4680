// Planted fault: a stub handler. FC 14 (read file record) answers every request, valid or not,
// with the same empty record list (byte count 0), as pymodbus 3.0's does. One defect: the
// handler does not read its request. Invalid requests answered normally and valid ones answered
// wrongly are that one defect, one finding.
#include "broken_server_common.hpp"

namespace {
broken::Action stub_file_record(const std::uint8_t* adu, std::size_t size,
                                std::vector<std::uint8_t>& reply, mbstorm::slave::DataModel&) {
    if (size < 8 || adu[7] != 0x14) return broken::Action::Default;
    reply.assign(adu, adu + 7);
    reply[2] = reply[3] = 0;
    mbstorm::codec::store_be16(reply.data() + 4, 3);
    reply.push_back(0x14);
    reply.push_back(0x00);
    return broken::Action::Reply;
}
}  // namespace

int main(int argc, char** argv) {
    broken::Faults f;
    f.on_frame = stub_file_record;
    return broken::main_with(argc, argv, f);
}
