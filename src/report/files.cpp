#include "report/files.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>

namespace mbstorm::report {

bool write_text_file(const std::string& path, std::string_view content, std::string& error) {
    std::FILE* f = std::fopen(path.c_str(), "wb");
    if (f == nullptr) {
        error = path + ": " + std::strerror(errno);
        return false;
    }
    const bool written = std::fwrite(content.data(), 1, content.size(), f) == content.size();
    const int write_errno = errno;
    const bool closed = std::fclose(f) == 0;
    if (!written || !closed) {
        error = path + ": " + std::strerror(written ? errno : write_errno);
        return false;
    }
    return true;
}

}  // namespace mbstorm::report
