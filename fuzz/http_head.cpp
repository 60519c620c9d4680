// libFuzzer harness: the request head `--metrics-listen` reads from anyone on the network, fed
// as the server's socket loop feeds it: in pieces (the first byte sets their size), the bytes
// after the two control bytes sent 1 to 4 times (the second byte) so that heads pass the
// 8 KiB cap. After each piece answer_received sees exactly the bytes so far (an exact-size
// heap copy: ASan reports any read past them). It must wait while the head is incomplete and
// within the cap, and then answer exactly: 431 past the cap, 400 for a malformed request
// line, 405 for another method, else the handler's reply for the path the request line holds.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>
#include <vector>

#include "net/http_server.hpp"

namespace {

using namespace mbstorm::net;

void check(bool ok) {
    if (!ok) std::abort();
}

HttpReply echo_path(std::string_view path) {
    return {200, "text/plain", std::string(path)};
}

// The answer owed for `sent` once answer_received gave a non-empty one.
void check_answer(std::string_view sent, const std::string& answer, bool too_large) {
    const std::size_t end = sent.find("\r\n\r\n");
    if (end == std::string_view::npos) {
        check(too_large && sent.size() > kMaxRequestHead);
        check(answer.starts_with("HTTP/1.1 431 "));
        return;
    }
    check(!too_large);
    const std::string_view head = sent.substr(0, end + 4);
    std::string method, path;
    if (!parse_http_request_line(head, method, path)) {
        check(answer.starts_with("HTTP/1.1 400 "));
    } else if (method != "GET" && method != "HEAD") {
        check(answer.starts_with("HTTP/1.1 405 "));
    } else {
        check(answer.starts_with("HTTP/1.1 200 "));
        // The path is the request line's, and a GET's body is the handler's echo of it.
        check(head.substr(0, head.find("\r\n")).find(method + " " + path) == 0);
        check(method == "HEAD" || answer.ends_with("\r\n\r\n" + path));
    }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size < 2) return 0;
    const std::size_t piece = 1 + std::size_t{data[0]} * 16;  // 1..4081, recv takes up to 4096
    const std::string_view once(reinterpret_cast<const char*>(data + 2), size - 2);
    std::string stream;
    for (int i = 0; i <= data[1] % 4; ++i) stream += once;
    for (std::size_t sent = 0; sent < stream.size();) {
        sent = std::min(stream.size(), sent + piece);
        const std::vector<char> copy(stream.begin(), stream.begin() + static_cast<long>(sent));
        const std::string_view so_far(copy.data(), copy.size());
        bool too_large = false;
        const std::string answer = answer_received(so_far, echo_path, too_large);
        if (answer.empty()) {
            check(!too_large && so_far.find("\r\n\r\n") == std::string_view::npos &&
                  so_far.size() <= kMaxRequestHead);
            continue;
        }
        check_answer(so_far, answer, too_large);
        return 0;  // the server reads no more once it answers
    }
    return 0;
}
