// A device whose back end is down: every request is answered with exception 04 (SERVER
// DEVICE FAILURE). It answers, so "does not answer" would be wrong: the fuzzer must say what
// it answered.
#include "broken_server_common.hpp"

namespace {
broken::Action always_failure(const std::uint8_t* adu, std::size_t size,
                              std::vector<std::uint8_t>& reply, mbstorm::slave::DataModel&) {
    if (size < 8) return broken::Action::Default;
    broken::exception_reply(adu, 0x04, reply);
    return broken::Action::Reply;
}
}  // namespace

int main(int argc, char** argv) {
    broken::Faults f;
    f.on_frame = always_failure;
    return broken::main_with(argc, argv, f);
}
