// Writing report text to disk.
#pragma once

#include <cstdio>
#include <string>
#include <string_view>

#include "util/error.hpp"

namespace mbstorm::report {

// Writes content to path (truncating); the path "-" is standard output. On failure an Io error,
// "<path>: <reason>".
Error write_text_file(const std::string& path, std::string_view content);

// Checks, before a long run, that write_text_file(path) can succeed, changing nothing: the
// path opens for writing (a missing file is created and removed again), its file system has
// room, and a character device that is not a terminal takes a probe byte (/dev/full does
// not). On failure an Io error like write_text_file's.
Error check_writable(const std::string& path);

// Closes a file written as the run goes (--hlog, --timeline) and sets `file` to null; an Io
// error (the reason alone, no path) when closing fails or `write_failed` says an earlier write
// did.
Error close_streamed_file(std::FILE*& file, bool write_failed);

}  // namespace mbstorm::report
