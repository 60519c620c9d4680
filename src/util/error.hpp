// The one error convention at layer boundaries (issue #30): a function that can fail returns an
// Error (or a Result<T>) by value, never a bool with a message out-parameter, an empty-string
// "success", a negative errno or an exception. Hot paths keep their own named enums
// (codec::CodecError, load::LinkInput, ...); exceptions stay inside the YAML and CLI parsing
// where a library throws, and are turned into an Error at that layer's edge. The CLI maps an
// Error to its exit code in one place (cli::exit_code_for). Standard library only.
#pragma once

#include <cassert>
#include <cstdint>
#include <iosfwd>
#include <string>
#include <string_view>
#include <utility>
#include <variant>

namespace mbstorm {

// What kind of failure, for callers that act on it (the CLI's exit code, a retry); the message
// says the rest. Every kind is the user's to act on: none of them is a bug in mbstorm.
enum class ErrorCode : std::uint8_t {
    Ok = 0,
    InvalidInput,  // a flag, a plan or a file's content that cannot be used as given
    NotFound,      // a file, a name or an address that is not there
    Io,            // reading or writing a file or stream failed
    Network,       // resolving, connecting, listening or talking to a peer failed
    Unsupported,   // this kernel, build or machine cannot do what was asked
    Refused,       // a safety rule said no (writes to a non-test target, a limit)
    Interrupted,   // stopped by a signal or a deadline before it finished
};

// "invalid input", "not found", ... (for logs and tests).
std::string_view error_code_name(ErrorCode code) noexcept;

// Why a file the user named could not be opened: NotFound when `path` is not there, else Io
// (permissions, a folder, a read error), so every reader answers "not there" the same way.
ErrorCode open_failure(const std::string& path);

class [[nodiscard]] Error {
  public:
    Error() = default;  // success
    Error(ErrorCode code, std::string message, std::string place = {})
        : code_(code), message_(std::move(message)), place_(std::move(place)) {}

    static Error none() { return {}; }

    bool ok() const noexcept { return code_ == ErrorCode::Ok; }
    ErrorCode code() const noexcept { return code_; }
    const std::string& message() const noexcept { return message_; }
    // Where in the input, when there is one: "scenario.yaml:12:3", "--json", a device path.
    const std::string& place() const noexcept { return place_; }

    // "<place>: <message>", or the message alone.
    std::string text() const;

    // The same error with "<prefix>: " before its message: what the caller was doing.
    Error& prefixed(std::string_view prefix);

    friend bool operator==(const Error&, const Error&) = default;

  private:
    ErrorCode code_ = ErrorCode::Ok;
    std::string message_;
    std::string place_;
};

// Its text(), for logs and test messages.
std::ostream& operator<<(std::ostream& out, const Error& error);
// A failed system call: "<what>: <strerror(err)>" (the message alone when `what` is empty),
// e.g. from_errno(ErrorCode::Io, errno, path) gives "out.json: No such file or directory".
Error from_errno(ErrorCode code, int err, std::string_view what);

// A value or the Error that stopped it; never both. std::expected is not in clang 14's library.
template <class T>
class [[nodiscard]] Result {
  public:
    Result(T value) : state_(std::in_place_index<0>, std::move(value)) {}  // NOLINT: implicit
    // A failure: `error` must not be Error::none() (there would be neither value nor error).
    Result(Error error) : state_(std::in_place_index<1>, std::move(error)) {  // NOLINT: implicit
        assert(!std::get<1>(state_).ok());
    }

    bool ok() const noexcept { return state_.index() == 0; }

    T& value() & { return std::get<0>(state_); }
    const T& value() const& { return std::get<0>(state_); }
    T&& value() && { return std::get<0>(std::move(state_)); }
    T& operator*() & { return value(); }
    const T& operator*() const& { return value(); }
    T* operator->() { return &value(); }
    const T* operator->() const { return &value(); }

    // The error; Error::none() when there is a value.
    const Error& error() const& {
        static const Error kNone;
        return ok() ? kNone : std::get<1>(state_);
    }
    Error error() && { return ok() ? Error{} : std::get<1>(std::move(state_)); }

  private:
    std::variant<T, Error> state_;
};

}  // namespace mbstorm
