// Planted fault: the framing bug of pymodbus 3.0. A read that leaves less than a whole MBAP
// header is taken for a bad frame and the connection is closed, so any client whose frame the
// network splits early is cut off. The server is also slow to read (each wakeup waits 5 ms),
// as a busy target is: a fuzzer that sends the next piece after a fixed short gap finds both
// pieces in one read and never sees the bug.
#include "broken_server_common.hpp"

int main(int argc, char** argv) {
    broken::Faults f;
    f.close_on_partial_header = true;
    f.read_delay_ms = 5;
    return broken::main_with(argc, argv, f);
}
