// Writing report text to disk.
#pragma once

#include <cstdio>
#include <string>
#include <string_view>

namespace mbstorm::report {

// Writes content to path (truncating); the path "-" is standard output. On failure returns false
// and sets error.
bool write_text_file(const std::string& path, std::string_view content, std::string& error);

// Checks, before a long run, that write_text_file(path) can succeed, changing nothing: the
// path opens for writing (a missing file is created and removed again), its file system has
// room, and a character device that is not a terminal takes a probe byte (/dev/full does
// not). On failure returns false and sets error like write_text_file.
bool check_writable(const std::string& path, std::string& error);

// Closes a file written as the run goes (--hlog, --timeline) and sets `file` to null; false,
// with error set, when closing fails or `write_failed` says an earlier write did.
bool close_streamed_file(std::FILE*& file, bool write_failed, std::string& error);

}  // namespace mbstorm::report
