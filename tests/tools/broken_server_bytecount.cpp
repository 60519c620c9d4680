// Planted fault: FC 10 (write multiple registers) takes its byte count from the quantity and
// never reads the byte count field: a request whose byte count disagrees is answered normally
// (v1.1b3 owes 03), with the data it carries cut or padded to the quantity. The quantity and
// address are checked as they should be. One field is wrong in the defect's reproducer, however
// many the case that found it had wrong: field-level minimisation makes the rest right.
#include "broken_server_common.hpp"

namespace {
constexpr std::size_t kCountAt = 7 + 5;  // MBAP header, then FC 10's byte count at PDU offset 5

broken::Action ignore_byte_count(const std::uint8_t* adu, std::size_t size,
                                 std::vector<std::uint8_t>& reply,
                                 mbstorm::slave::DataModel& model) {
    if (size <= kCountAt || adu[7] != 0x10) return broken::Action::Default;
    const std::size_t bytes = 2u * mbstorm::codec::load_be16(adu + 10);
    if (bytes > 0xFF) return broken::Action::Default;  // the quantity check answers it
    std::vector<std::uint8_t> as_read(adu, adu + kCountAt + 1);
    as_read[kCountAt] = static_cast<std::uint8_t>(bytes);
    as_read.insert(as_read.end(), adu + kCountAt + 1, adu + size);
    as_read.resize(kCountAt + 1 + bytes);
    mbstorm::codec::store_be16(as_read.data() + 4, static_cast<std::uint16_t>(as_read.size() - 6));
    broken::handle_default(as_read.data(), as_read.size(), reply, model);
    return broken::Action::Reply;
}
}  // namespace

int main(int argc, char** argv) {
    broken::Faults f;
    f.on_frame = ignore_byte_count;
    return broken::main_with(argc, argv, f);
}
