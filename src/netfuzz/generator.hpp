// The case generator: structure-aware (every function code, values at and around every limit,
// MBAP and transport mutations, stateful write/read sequences, mutations of recorded valid
// traffic) or, for comparison, naive (random PDU bytes in a valid MBAP frame).
// Deterministic: the same seed and the same feedback give the same cases.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "netfuzz/case.hpp"
#include "netfuzz/coverage_map.hpp"
#include "netfuzz/device_model.hpp"
#include "netfuzz/oracle.hpp"
#include "netfuzz/rng.hpp"

namespace mbstorm::netfuzz {

struct GeneratorOptions {
    std::uint64_t seed = 1;
    std::uint8_t unit = 1;
    bool naive = false;
    // Transport and stateful cases need their own connections and round trips; this is the
    // share (per mille) of cases of those kinds.
    unsigned isolated_per_mille = 10;
    StateRange state;  // where stateful cases write and read back
    // The user's own dictionary (--dict): 16-bit words used as addresses and values, longer
    // tokens spliced into requests.
    std::vector<std::uint16_t> dict_words;
    std::vector<std::vector<std::uint8_t>> dict_tokens;
    // RTU or ASCII: cases are made in MBAP as always, then reframed (cases that only mean
    // something in MBAP give way to the framing's own transport mutations), and run alone.
    codec::Framing framing = codec::Framing::Mbap;
    bool serial_line = false;             // a serial line: one link, silences delimit frames
    std::uint32_t intercharacter_us = 0;  // the line's t1.5 (serial only)
    // The device's map (null or empty: none known). With one, a share of cases is aimed
    // inside it (in-map, map-edge) and stateful cases write where the device keeps data.
    const DeviceModel* model = nullptr;
    // Function codes the target answered 01 at discovery: not aimed at the map.
    std::array<bool, 256> unsupported{};
};

// 16-bit values worth writing and reading back: boundaries, sign bits, all-ones patterns and
// common sentinel words.
const std::vector<std::uint16_t>& interesting_words();

class Generator {
  public:
    explicit Generator(const GeneratorOptions& options);

    void next(Case& out);
    // The device's map, once known (the campaign learns it after its first looks), and the
    // state range that goes with it. Null or empty: none.
    // A target that pauses after exceptions gains nothing from pipelining (it drops what
    // follows an exception): a tenth of its cases, at least, are stateful and transport ones.
    void use_model(const DeviceModel* model, const StateRange& state) {
        options_.model = model;
        options_.state = state;
        edges_.clear();
        if (model && model->pauses_after_exceptions())
            options_.isolated_per_mille = std::max(options_.isolated_per_mille, 100u);
    }
    // A class that crashed or hung the target is drawn 16 times less often from now on.
    void deprioritise(std::uint8_t function, MutationClass cls);

    // Coverage-guided runs (generator_coverage.cpp): a case that reached new edges joins the
    // corpus, whose entries then make half the cases; constants the target compared its input
    // against become field values.
    // Its failed comparisons give the next cases: an operand found in one of its frames
    // replaced by the other (input-to-state, as AFL++'s cmplog), alone and together with the
    // comparison made next (a compiler may test `a == X && b == Y` as one branch).
    // `rarest_edge`: the map cell of the rarest edge the case hit (CoverageSample).
    void add_to_corpus(const Case& c, const std::vector<Comparison>& comparisons = {},
                       std::uint32_t rarest_edge = 0);
    // Half the corpus picks go to the entry whose rarest edge the fewest cases have hit so
    // far (counted by `map`), as FairFuzz does: what reaches a rare branch is mutated until
    // the branch is no longer rare. Without a map, the newest entries are favoured.
    void favour_rare_edges(const CoverageMap* map) noexcept { edge_counts_ = map; }
    // The corpus entry the next coverage mutation starts from.
    std::size_t pick_corpus_entry();
    void add_compared(const std::vector<std::uint16_t>& words,
                      const std::vector<std::uint8_t>& bytes);
    std::size_t corpus_size() const noexcept { return coverage_corpus_.size(); }
    // Saved entries of an earlier run: run before anything else, they join the corpus again
    // as they reach what they reached then.
    void resume(std::vector<Case> entries) {
        for (auto it = entries.rbegin(); it != entries.rend(); ++it) push_solved(*it, nullptr);
    }
    const std::vector<Case>& corpus() const noexcept { return coverage_corpus_; }

    // The structured request PDUs (limits of every function code), for tests.
    const std::vector<std::vector<std::uint8_t>>& seeds() const noexcept { return seeds_; }

  private:
    void structured(Case& out, MutationClass forced = MutationClass::Count);
    void naive(Case& out);
    void isolated(Case& out);
    void mangled_frame(Case& out, std::uint32_t roll);
    void slow_frame(Case& out, std::uint32_t roll, std::vector<std::uint8_t> f);
    void mutate_recorded(Case& out);
    void stateful(Case& out, bool cross);
    std::vector<std::uint8_t> stateful_write(Case& out, std::uint8_t fc, std::uint16_t base,
                                             std::uint32_t room, std::uint16_t& qty, bool& coils);
    void read_write_over(Case& out, codec::Request& w, std::vector<std::uint8_t>& payload,
                         std::uint32_t room, std::uint16_t qty);
    void read_back(Case& out, bool cross, std::uint8_t fc, std::uint16_t base, std::uint16_t qty,
                   bool coils);
    void burst_split(Case& out);
    void corpus_mutation(Case& out);
    void mutate_frame(std::vector<std::uint8_t>& f);
    std::uint16_t compared_word();
    void solve_comparisons(const Case& c, const std::vector<Comparison>& comparisons);
    std::vector<std::size_t> rarest_first(const std::vector<Comparison>& comparisons,
                                          std::vector<const std::uint32_t*>& counts);
    // Model-aimed cases (generator_map.cpp).
    bool has_model() const noexcept { return options_.model && !options_.model->empty(); }
    void in_map(Case& out);
    void map_edge(Case& out);
    bool pick_map_function(std::uint8_t& fc);
    void build_edges();
    // An address in the map's coils or holding registers: with `room` items after it in the
    // same range, or (room 0) near a range's start, where most of the range lies ahead.
    std::uint16_t model_address(bool coils, std::uint16_t room);
    std::uint32_t map_room(bool coils, std::uint16_t address) const;
    std::uint16_t word();  // an interesting or dictionary word
    std::uint16_t state_address(std::uint16_t room);
    std::vector<std::uint8_t> frame(const std::vector<std::uint8_t>& pdu, std::uint8_t unit);
    const std::vector<std::uint8_t>& next_seed();
    const std::vector<std::uint8_t>& valid_seed();
    std::uint16_t tid() noexcept { return tid_++; }
    bool deprioritised(const Case& c) const noexcept;
    void adapt_to_framing(Case& out);
    void framing_transport(Case& out);

    GeneratorOptions options_;
    Rng rng_;
    std::vector<std::vector<std::uint8_t>> seeds_;  // shuffled structured PDUs
    std::vector<std::size_t> valid_seeds_;          // indexes of seeds the codec accepts
    std::vector<std::size_t> invalid_seeds_;        // and of those it owes an exception
    std::vector<std::vector<std::uint8_t>> corpus_;
    std::size_t seed_cursor_ = 0;
    std::uint32_t split_cursor_ = 0;
    std::uint32_t burst_cursor_ = 0;
    std::uint32_t unit_cursor_ = 0;  // pairwise walk: unit-id classes x function codes
    std::vector<std::vector<std::size_t>> seeds_by_function_;  // valid seed indexes per FC
    std::uint16_t tid_;
    struct Edge {
        std::uint8_t function;
        std::uint16_t address, quantity;
        bool second_range;  // FC17: the write range at the edge
    };
    std::vector<Edge> edges_;  // map-edge requests, walked in turn
    std::vector<Case> coverage_corpus_;
    std::vector<std::uint32_t> corpus_rare_edge_;  // per entry: its rarest edge when it joined
    const CoverageMap* edge_counts_ = nullptr;
    // Input-to-state cases, run before any other: first the case of the comparison the fewest
    // corpus entries have made by now (`count`, null for a resumed entry: first of all), of
    // equally rare ones the newest. Each entry gives up to 96: on a slow target, the
    // comparisons every case makes (its framing's, its poll loop's) would otherwise bury a
    // request handler's for minutes.
    struct Solved {
        const std::uint32_t* count = nullptr;
        std::uint64_t order = 0;
        Case c;
    };
    std::vector<Solved> solved_;
    std::uint64_t solved_order_ = 0;
    void push_solved(Case c, const std::uint32_t* count);
    Case pop_solved();
    // How many corpus entries made each comparison (size, a, b): the rarest are solved first.
    std::unordered_map<std::string, std::uint32_t> comparisons_seen_;
    std::vector<std::uint16_t> compared_words_;
    std::vector<std::uint8_t> compared_bytes_;
    std::size_t edge_cursor_ = 0;
    std::array<std::uint32_t, 256 * static_cast<std::size_t>(MutationClass::Count) / 32 + 1>
        deprioritised_{};
};

// Builds every structured request PDU (not shuffled).
std::vector<std::vector<std::uint8_t>> structured_pdus();

}  // namespace mbstorm::netfuzz
