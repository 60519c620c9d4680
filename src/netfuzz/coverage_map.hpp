// The coverage map of a grey-box run (mbstorm fuzz --coverage): a System V shared-memory
// segment the target writes its edge hit counts to, AFL's convention (its id in __AFL_SHM_ID,
// its size in AFL_MAP_SIZE), so targets built with AFL++'s compilers or with clang and
// mbstorm's runtime (coverage/mbstorm_coverage.c) both work. Past the map, mbstorm's runtime
// logs the operands of the comparisons the target made.
//
// Per case: clear() before it, collect() after it. Hit counts are bucketed as AFL does (1, 2,
// 3, 4-7, 8-15, 16-31, 32-127, 128+); a case is new when it sets a bucket bit no case set
// before. A case that sets new bits is calibrated (AFL's way): run again, the cells whose bucket
// differs between its runs count hits of a loop that turns with timing (a poll loop, a read
// that returned part of a request), not with the input. They are marked unstable and make no
// case new from then on, so that a run repeats with its seed. Apart from that, clear() keeps which
// edges were ever hit, by anything the target did (its start-up, discovery, confirmation runs too),
// for --coverage-report.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "util/error.hpp"

namespace mbstorm::netfuzz {

struct Comparison {
    std::uint8_t size = 0;  // operand bytes: 1, 2, 4 or 8
    std::uint64_t a = 0, b = 0;
};

struct CoverageSample {
    bool new_bits = false;  // a bucket bit no case set before, in a cell not unstable
    std::vector<std::uint32_t> new_cells;  // the cells of those bits
    std::uint32_t new_edges = 0;           // edges never hit before
    std::uint32_t edges = 0;               // edges this case hit
    // Of the edges this case hit, the one the fewest cases of the run have hit (counting this
    // one): a corpus entry's claim to more runs (Generator favours entries of rare edges).
    std::uint32_t rarest_edge = 0;
    // Constants the target compared its input against (mbstorm's runtime only), deduplicated.
    std::vector<std::uint16_t> compared_words;
    std::vector<std::uint8_t> compared_bytes;
    // The comparisons this case made that failed, in the order it made them: where a request
    // carries one operand, the other put there passes the comparison.
    std::vector<Comparison> comparisons;
};

class CoverageMap {
  public:
    CoverageMap() = default;
    CoverageMap(const CoverageMap&) = delete;
    CoverageMap& operator=(const CoverageMap&) = delete;
    ~CoverageMap();

    // Creates and attaches the segment (`map_size` a power of two, 64 B .. 16 MiB). It is
    // marked for removal at once (Linux lets the target attach it still), so no segment
    // outlives mbstorm however it ends. InvalidInput for a bad size, Unsupported when this
    // machine gives no shared memory.
    Error create(std::size_t map_size);
    // Puts __AFL_SHM_ID and AFL_MAP_SIZE in this process's environment, for the target command.
    void export_environment() const;

    // Remembers the edges hit since the last clear (reached()), then zeroes the map.
    void clear() noexcept;
    CoverageSample collect();
    // Whether the map cell `index` (an edge's guard) was ever hit during the run.
    bool reached(std::size_t index) const noexcept;
    // How many collected cases hit the map cell `index`.
    std::uint32_t cases_hitting(std::size_t index) const noexcept {
        return index < cases_hitting_.size() ? cases_hitting_[index] : 0;
    }

    // Calibration: the map bucketed as the case left it (before the next clear()), then,
    // after each run of the case again, the cells whose bucket differs from `first` marked
    // unstable (how many were newly marked). `still_new` says whether `s` has a new bit left
    // in a cell that is not unstable.
    std::vector<std::uint8_t> trace() const;
    std::uint32_t mark_unstable(const std::vector<std::uint8_t>& first);
    bool still_new(const CoverageSample& s) const noexcept;
    std::uint32_t unstable_cells() const noexcept { return unstable_count_; }

    std::uint32_t edges_seen() const noexcept { return edges_seen_; }
    std::size_t map_size() const noexcept { return map_size_; }
    int id() const noexcept { return id_; }
    // The map as the target left it (tests).
    const std::uint8_t* map() const noexcept { return map_; }

  private:
    int id_ = -1;
    std::uint8_t* map_ = nullptr;
    std::size_t map_size_ = 0;
    std::vector<std::uint8_t> virgin_;  // bucket bits no case has set yet (AFL's virgin map)
    std::vector<bool> reached_;         // cells hit before the last clear()
    std::vector<std::uint32_t> cases_hitting_;  // per cell: collected cases that hit it
    std::vector<bool> unstable_;                // cells whose bucket changed in calibration
    std::uint32_t unstable_count_ = 0;
    std::uint32_t edges_seen_ = 0;
    std::vector<std::uint8_t> words_known_;  // a bit per 16-bit word already reported
};

// AFL's bucket of a hit count, as one bit (0 for no hit).
std::uint8_t hit_bucket(std::uint8_t hits) noexcept;

// The size of the comparison log mbstorm's runtime keeps past the map.
std::size_t comparison_log_size() noexcept;

}  // namespace mbstorm::netfuzz
