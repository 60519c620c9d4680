// Whether this test binary (and so the mbstorm binary of the same build) runs under
// AddressSanitizer: its shadow memory reserves terabytes of address space, so tests that bound
// memory by address space (RLIMIT_AS, ulimit -v) bound it another way or not at all there.
#pragma once

namespace mbstorm::test {

#if defined(__SANITIZE_ADDRESS__)
inline constexpr bool kAddressSanitizer = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
inline constexpr bool kAddressSanitizer = true;
#else
inline constexpr bool kAddressSanitizer = false;
#endif
#else
inline constexpr bool kAddressSanitizer = false;
#endif

}  // namespace mbstorm::test
