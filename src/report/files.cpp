#include "report/files.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

namespace mbstorm::report {

Error write_text_file(const std::string& path, std::string_view content) {
    if (path == "-") {
        if (std::fwrite(content.data(), 1, content.size(), stdout) != content.size() ||
            std::fflush(stdout) != 0)
            return from_errno(ErrorCode::Io, errno, "standard output");
        return Error::none();
    }
    std::FILE* f = std::fopen(path.c_str(), "wb");
    if (f == nullptr) return from_errno(ErrorCode::Io, errno, path);
    const bool written = std::fwrite(content.data(), 1, content.size(), f) == content.size();
    const int write_errno = errno;
    const bool closed = std::fclose(f) == 0;
    if (!written || !closed) return from_errno(ErrorCode::Io, written ? errno : write_errno, path);
    return Error::none();
}

Error check_writable(const std::string& path) {
    const bool existed = ::access(path.c_str(), F_OK) == 0;
    const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_CLOEXEC | O_NOCTTY, 0666);
    if (fd < 0) return from_errno(ErrorCode::Io, errno, path);
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
    if (problem != 0) return from_errno(ErrorCode::Io, problem, path);
    return Error::none();
}

Error close_streamed_file(std::FILE*& file, bool write_failed) {
    if (file == nullptr) return Error::none();
    const int saved = errno;
    const bool closed = std::fclose(file) == 0;
    file = nullptr;
    if (write_failed || !closed) return from_errno(ErrorCode::Io, closed ? saved : errno, "");
    return Error::none();
}

}  // namespace mbstorm::report
