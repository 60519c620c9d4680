// Planted fault: a framing bug that only shows with a split header. The server assumes the
// 7-byte MBAP header arrives in one read and throws away a partial one, so the rest of the
// frame is parsed as a new header: the request goes unanswered or the connection closes.
#include "broken_server_common.hpp"

int main(int argc, char** argv) {
    broken::Faults f;
    f.drop_partial_header = true;
    return broken::main_with(argc, argv, f);
}
