// Planted fault: frames with a protocol id other than 0 are answered instead of discarded
// (the Modbus TCP implementation guide says to discard them).
#include "broken_server_common.hpp"

int main(int argc, char** argv) {
    broken::Faults f;
    f.answer_any_protocol = true;
    return broken::main_with(argc, argv, f);
}
