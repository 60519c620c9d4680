// A set of function code bytes and how a user lists one: "1-6,15,16" (codes 1..255, decimal
// or 0x hex, ranges inclusive). The one syntax of `serve --tls-role ROLE=LIST` and of a device
// file's `tls_roles:`.
#pragma once

#include <bitset>
#include <string>
#include <string_view>

namespace mbstorm::codec {

using FunctionSet = std::bitset<256>;

// "" on success, else what is wrong with which item.
std::string parse_function_set(std::string_view list, FunctionSet& out);

// The set as such a list, ranges folded ("1-6,15-16"); "" for an empty set.
std::string format_function_set(const FunctionSet& set);

}  // namespace mbstorm::codec
