// Which event source the workers run on: io_uring, or epoll where io_uring is refused (see
// event_loop.hpp). Chosen once per run or server.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

#include "util/error.hpp"

namespace mbstorm::net {

enum class Backend : std::uint8_t { IoUring, Epoll };
enum class BackendChoice : std::uint8_t { Auto, IoUring, Epoll };

std::string_view backend_name(Backend backend) noexcept;
// "auto", "io_uring" or "epoll"; false for anything else.
bool parse_backend_choice(std::string_view text, BackendChoice& choice) noexcept;

// What a run or a server uses: io_uring when chosen or when `auto` finds it usable (with
// provided-buffer rings when `need_buf_ring`), else epoll. Fails (Unsupported, saying why)
// only when io_uring was asked for and cannot be had. `why` says why auto fell back.
struct BackendDecision {
    Backend backend = Backend::IoUring;
    std::string why;  // empty when io_uring runs or epoll was asked for
};
Result<BackendDecision> choose_backend(BackendChoice choice, bool need_buf_ring);

}  // namespace mbstorm::net
