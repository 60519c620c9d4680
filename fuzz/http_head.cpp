// libFuzzer harness: the request head `--metrics-listen` reads from anyone on the network.
// parse_http_request_line must accept or refuse any bytes without reading past them, and a
// method and path it accepts are parts of the head's first line.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>

#include "net/http_server.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string_view head(reinterpret_cast<const char*>(data), size);
    std::string method, path;
    if (!mbstorm::net::parse_http_request_line(head, method, path)) return 0;
    const std::string_view line = head.substr(0, head.find("\r\n"));  // the parser's line
    if (line.find(method) == std::string_view::npos || line.find(path) == std::string_view::npos)
        std::abort();
    return 0;
}
