#include "util/error.hpp"

#include <cstring>
#include <filesystem>
#include <ostream>
#include <system_error>

namespace mbstorm {

std::string_view error_code_name(ErrorCode code) noexcept {
    switch (code) {
        case ErrorCode::Ok:
            return "ok";
        case ErrorCode::InvalidInput:
            return "invalid input";
        case ErrorCode::NotFound:
            return "not found";
        case ErrorCode::Io:
            return "i/o error";
        case ErrorCode::Network:
            return "network error";
        case ErrorCode::Unsupported:
            return "unsupported";
        case ErrorCode::Refused:
            return "refused";
        case ErrorCode::Interrupted:
            return "interrupted";
    }
    return "unknown";
}

ErrorCode open_failure(const std::string& path) {
    std::error_code ec;
    return std::filesystem::exists(path, ec) ? ErrorCode::Io : ErrorCode::NotFound;
}

std::string Error::text() const {
    if (place_.empty()) return message_;
    return place_ + ": " + message_;
}

Error& Error::prefixed(std::string_view prefix) {
    message_.insert(0, std::string(prefix) + ": ");
    return *this;
}

std::ostream& operator<<(std::ostream& out, const Error& error) {
    return out << error.text();
}

Error from_errno(ErrorCode code, int err, std::string_view what) {
    std::string message(what);
    if (!message.empty()) message += ": ";
    message += std::strerror(err);
    return Error(code, std::move(message));
}

}  // namespace mbstorm
