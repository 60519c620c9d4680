#include "report/files.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

namespace mbstorm::report {

bool write_text_file(const std::string& path, std::string_view content, std::string& error) {
    if (path == "-") {
        if (std::fwrite(content.data(), 1, content.size(), stdout) != content.size() ||
            std::fflush(stdout) != 0) {
            error = std::string("standard output: ") + std::strerror(errno);
            return false;
        }
        return true;
    }
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

bool check_writable(const std::string& path, std::string& error) {
    auto fail = [&](int code) {
        error = path + ": " + std::strerror(code);
        return false;
    };
    const bool existed = ::access(path.c_str(), F_OK) == 0;
    const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_CLOEXEC | O_NOCTTY, 0666);
    if (fd < 0) return fail(errno);
    int problem = 0;
    struct stat st {};
    if (::fstat(fd, &st) != 0) {
        problem = errno;
    } else if (S_ISREG(st.st_mode)) {
        struct statvfs vfs {};
        if (::fstatvfs(fd, &vfs) == 0 && vfs.f_bavail == 0) problem = ENOSPC;
    } else if (S_ISCHR(st.st_mode) && !::isatty(fd)) {
        const char probe = '\n';
        if (::write(fd, &probe, 1) != 1) problem = errno;
    }
    ::close(fd);
    if (!existed) ::unlink(path.c_str());
    return problem == 0 || fail(problem);
}

bool close_streamed_file(std::FILE*& file, bool write_failed, std::string& error) {
    if (file == nullptr) return true;
    const int saved = errno;
    const bool closed = std::fclose(file) == 0;
    file = nullptr;
    if (write_failed || !closed) {
        error = std::strerror(closed ? saved : errno);
        return false;
    }
    return true;
}

}  // namespace mbstorm::report
