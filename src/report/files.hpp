// Writing report text to disk.
#pragma once

#include <string>
#include <string_view>

namespace mbstorm::report {

// Writes content to path (truncating). On failure returns false and sets error.
bool write_text_file(const std::string& path, std::string_view content, std::string& error);

}  // namespace mbstorm::report
