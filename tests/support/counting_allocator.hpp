// Replaces the global operator new/delete of a test binary with versions that count every
// allocation, so a test can show that a hot path allocates nothing. Include it from exactly
// one source file per test binary: it defines the replacement operators.
#pragma once

#include <atomic>
#include <cstdint>
#include <cstdlib>
#include <new>

namespace mbstorm::testing {

inline std::atomic<std::uint64_t> g_allocation_count{0};

// Allocations made so far by any thread of this process (take differences).
inline std::uint64_t allocations() noexcept {
    return g_allocation_count.load(std::memory_order_relaxed);
}

}  // namespace mbstorm::testing

// The replacements pair malloc with free on purpose; GCC cannot see that they belong together.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
#endif

void* operator new(std::size_t size) {
    mbstorm::testing::g_allocation_count.fetch_add(1, std::memory_order_relaxed);
    if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
    throw std::bad_alloc();
}
void* operator new[](std::size_t size) {
    return ::operator new(size);
}
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
    mbstorm::testing::g_allocation_count.fetch_add(1, std::memory_order_relaxed);
    return std::malloc(size == 0 ? 1 : size);
}
void* operator new[](std::size_t size, const std::nothrow_t& tag) noexcept {
    return ::operator new(size, tag);
}
void operator delete(void* p) noexcept {
    std::free(p);
}
void operator delete[](void* p) noexcept {
    std::free(p);
}
void operator delete(void* p, std::size_t) noexcept {
    std::free(p);
}
void operator delete[](void* p, std::size_t) noexcept {
    std::free(p);
}
