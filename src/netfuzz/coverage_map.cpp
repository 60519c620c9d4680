#include "netfuzz/coverage_map.hpp"

#include <sys/ipc.h>
#include <sys/shm.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <string>

#include <fmt/format.h>

namespace mbstorm::netfuzz {
namespace {

// The comparison log past the map, as coverage/mbstorm_coverage.c writes it.
constexpr std::uint32_t kCmpMagic = 0x504D434DU;
constexpr std::size_t kCmpSites = 4096;
constexpr std::size_t kCmpEntries = 1024;
constexpr std::uint32_t kConstantOperand = 0x80;

struct CmpEntry {
    std::uint32_t size;
    std::uint32_t reserved;
    std::uint64_t a, b;
};

struct CmpLog {
    std::uint32_t magic;
    std::uint32_t count;
    std::uint8_t sites[kCmpSites / 8];
    CmpEntry entries[kCmpEntries];
};

constexpr std::size_t kMinMap = 64, kMaxMap = std::size_t{1} << 24;

}  // namespace

std::uint8_t hit_bucket(std::uint8_t hits) noexcept {
    if (hits == 0) return 0;
    if (hits <= 3) return static_cast<std::uint8_t>(1u << (hits - 1));  // 1, 2, 3
    if (hits <= 7) return 8;
    if (hits <= 15) return 16;
    if (hits <= 31) return 32;
    if (hits <= 127) return 64;
    return 128;
}

std::size_t comparison_log_size() noexcept {
    return sizeof(CmpLog);
}

CoverageMap::~CoverageMap() {
    if (map_) ::shmdt(map_);
}

Error CoverageMap::create(std::size_t map_size) {
    if (map_size < kMinMap || map_size > kMaxMap || (map_size & (map_size - 1))) {
        return Error(ErrorCode::InvalidInput,
                     fmt::format("coverage map size {} is not a power of two from {} to {}",
                                 map_size, kMinMap, kMaxMap));
    }
    id_ = ::shmget(IPC_PRIVATE, map_size + sizeof(CmpLog), IPC_CREAT | IPC_EXCL | 0600);
    if (id_ < 0) {
        return Error(
            ErrorCode::Unsupported,
            fmt::format("cannot create the coverage map: shmget: {}", std::strerror(errno)));
    }
    void* at = ::shmat(id_, nullptr, 0);
    // Marked for removal now: it goes when the last process detaches, however mbstorm ends.
    ::shmctl(id_, IPC_RMID, nullptr);
    if (at == reinterpret_cast<void*>(-1)) {
        id_ = -1;
        return Error(
            ErrorCode::Unsupported,
            fmt::format("cannot attach the coverage map: shmat: {}", std::strerror(errno)));
    }
    map_ = static_cast<std::uint8_t*>(at);
    map_size_ = map_size;
    virgin_.assign(map_size, 0xFF);
    reached_.assign(map_size, false);
    cases_hitting_.assign(map_size, 0);
    unstable_.assign(map_size, false);
    unstable_count_ = 0;
    words_known_.assign(65536 / 8 + 256 / 8, 0);
    clear();
    return Error::none();
}

void CoverageMap::export_environment() const {
    ::setenv("__AFL_SHM_ID", std::to_string(id_).c_str(), 1);
    ::setenv("AFL_MAP_SIZE", std::to_string(map_size_).c_str(), 1);
}

void CoverageMap::clear() noexcept {
    if (!map_) return;
    // Most of the map is zero: look at eight bytes at a time.
    for (std::size_t i = 0; i < map_size_; i += 8) {
        std::uint64_t word;
        std::memcpy(&word, map_ + i, 8);
        if (!word) continue;
        for (std::size_t k = i; k < i + 8; ++k)
            if (map_[k]) reached_[k] = true;
    }
    std::memset(map_, 0, map_size_);
    auto* log = reinterpret_cast<CmpLog*>(map_ + map_size_);
    log->count = 0;
    std::memset(log->sites, 0, sizeof log->sites);
}

namespace {

// Adds `v` to `out` unless `known` (a bit per value) has it already.
template <typename T>
void add_once(std::vector<T>& out, std::uint8_t* known, std::uint32_t v) {
    std::uint8_t& byte = known[v / 8];
    const auto bit = static_cast<std::uint8_t>(1u << (v % 8));
    if (byte & bit) return;
    byte |= bit;
    out.push_back(static_cast<T>(v));
}

// The operands of a comparison as values a request can carry: bytes, 16-bit words, and both
// halves of a 32-bit one (two registers). Of a comparison against a constant, the constant.
void harvest(const CmpEntry& e, std::uint8_t* known_words, std::uint8_t* known_bytes,
             CoverageSample& s) {
    const std::uint32_t size = e.size & ~kConstantOperand;
    if (s.comparisons.size() < 256)
        s.comparisons.push_back(Comparison{static_cast<std::uint8_t>(size), e.a, e.b});
    const bool first_constant = (e.size & kConstantOperand) != 0;
    for (const std::uint64_t v : {e.a, e.b}) {
        if (size == 1) {
            add_once(s.compared_bytes, known_bytes, static_cast<std::uint32_t>(v & 0xFF));
        } else if (v <= 0xFFFF) {
            add_once(s.compared_words, known_words, static_cast<std::uint32_t>(v));
        } else if (v <= 0xFFFFFFFFu) {
            add_once(s.compared_words, known_words, static_cast<std::uint32_t>(v >> 16));
            add_once(s.compared_words, known_words, static_cast<std::uint32_t>(v & 0xFFFF));
        }
        if (first_constant) break;
    }
}

}  // namespace

bool CoverageMap::reached(std::size_t index) const noexcept {
    return index < map_size_ && (reached_[index] || map_[index] != 0);
}

CoverageSample CoverageMap::collect() {
    CoverageSample s;
    if (!map_) return s;
    // Most of the map is zero: look at eight bytes at a time.
    for (std::size_t i = 0; i < map_size_; i += 8) {
        std::uint64_t word;
        std::memcpy(&word, map_ + i, 8);
        if (!word) continue;
        for (std::size_t k = i; k < i + 8; ++k) {
            const std::uint8_t b = hit_bucket(map_[k]);
            if (!b) continue;
            ++s.edges;
            const std::uint32_t hits = ++cases_hitting_[k];
            if (s.edges == 1 || hits < cases_hitting_[s.rarest_edge])
                s.rarest_edge = static_cast<std::uint32_t>(k);
            if (!(virgin_[k] & b)) continue;
            if (!unstable_[k]) {
                s.new_bits = true;
                s.new_cells.push_back(static_cast<std::uint32_t>(k));
            }
            if (virgin_[k] == 0xFF) {
                ++s.new_edges;
                ++edges_seen_;
            }
            virgin_[k] = static_cast<std::uint8_t>(virgin_[k] & ~b);
        }
    }
    const auto* log = reinterpret_cast<const CmpLog*>(map_ + map_size_);
    if (log->magic == kCmpMagic) {
        const std::uint32_t n = std::min<std::uint32_t>(log->count, kCmpEntries);
        for (std::uint32_t i = 0; i < n; ++i)
            harvest(log->entries[i], words_known_.data(), words_known_.data() + 65536 / 8, s);
    }
    return s;
}

std::vector<std::uint8_t> CoverageMap::trace() const {
    std::vector<std::uint8_t> out(map_size_);
    for (std::size_t k = 0; k < map_size_; ++k) out[k] = hit_bucket(map_[k]);
    return out;
}

std::uint32_t CoverageMap::mark_unstable(const std::vector<std::uint8_t>& first) {
    std::uint32_t marked = 0;
    for (std::size_t k = 0; k < map_size_ && k < first.size(); ++k) {
        if (unstable_[k] || hit_bucket(map_[k]) == first[k]) continue;
        unstable_[k] = true;
        ++marked;
    }
    unstable_count_ += marked;
    return marked;
}

bool CoverageMap::still_new(const CoverageSample& s) const noexcept {
    for (const std::uint32_t k : s.new_cells)
        if (k < map_size_ && !unstable_[k]) return true;
    return false;
}

}  // namespace mbstorm::netfuzz
