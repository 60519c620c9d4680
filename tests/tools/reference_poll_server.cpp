// The reference handler (slave/handler) behind broken_server_common.hpp's poll() loop with no
// fault planted: the correct server of the grey-box tests (tests/scripts/
// fuzz_coverage_multi_fault.sh), built there with coverage as the multi-fault targets are, on
// which a coverage run must find nothing.
#include "broken_server_common.hpp"

int main(int argc, char** argv) {
    return broken::main_with(argc, argv, broken::Faults{});
}
