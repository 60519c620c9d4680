// libFuzzer harness: function codes as a user writes them (`--fc`, a scenario's `function:`,
// `--tls-role ROLE=LIST`, a device file's `tls_roles:`). The whole input is read both as one
// code (parse_function_code, function_from_name) and as a list (parse_function_set).
// Invariants: an accepted code is 1..127 and reads back from its decimal, its hex and (when it
// has one) its name; a name is accepted only as the name of its own code; a set reads back
// from its own print, and prints the same again; a refusal says why.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>

#include "codec/function_code.hpp"
#include "codec/function_set.hpp"

namespace {

using namespace mbstorm::codec;

void check(bool ok) {
    if (!ok) std::abort();
}

// The code `fc` must come back from `text`.
void reads_as(std::string_view text, std::uint8_t fc) {
    std::uint8_t again = 0;
    check(parse_function_code(text, again).empty() && again == fc);
}

void one_code(std::string_view text) {
    std::uint8_t fc = 0;
    const std::string error = parse_function_code(text, fc);
    if (!error.empty()) {
        // Refused: the message quotes the text, so the user sees what was read.
        check(error.find(text) != std::string::npos);
        return;
    }
    check(fc >= 1 && fc <= 0x7F);
    reads_as(std::to_string(fc), fc);
    reads_as(function_label(fc).substr(0, 4), fc);  // "0x10", the hex every output prints
    const std::string_view name = function_name(fc);
    if (!name.empty()) reads_as(name, fc);
    std::uint8_t by_name = 0;
    if (function_from_name(text, by_name)) check(by_name == fc && function_name(fc) == text);
}

void code_set(std::string_view text) {
    FunctionSet set;
    const std::string error = parse_function_set(text, set);
    if (!error.empty()) return;
    check(!set.test(0) && set.any());  // codes are 1..255; an empty list is refused
    const std::string printed = format_function_set(set);
    FunctionSet again;
    check(parse_function_set(printed, again).empty() && again == set);
    check(format_function_set(again) == printed);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string_view text(reinterpret_cast<const char*>(data), size);
    one_code(text);
    code_set(text);
    return 0;
}
