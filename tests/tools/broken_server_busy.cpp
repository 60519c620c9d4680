// Not a bug but a hostile condition: a server that answers exception 06 (server device busy)
// to three of every four requests, as an overloaded gateway does. The fuzzer must say that
// most cases were wasted and slow down, not report "no findings" as if it had tested much.
#include "broken_server_common.hpp"

namespace {
broken::Action mostly_busy(const std::uint8_t* adu, std::size_t size,
                           std::vector<std::uint8_t>& reply, mbstorm::slave::DataModel&) {
    static unsigned frames = 0;
    if (size < 8 || ++frames % 4 == 0) return broken::Action::Default;
    broken::exception_reply(adu, 0x06, reply);
    return broken::Action::Reply;
}
}  // namespace

int main(int argc, char** argv) {
    broken::Faults f;
    f.on_frame = mostly_busy;
    return broken::main_with(argc, argv, f);
}
