// Produces the next request of a thread: picks an operation by weight, draws its address from
// the operation's distribution, generates write values, and encodes the whole ADU straight into
// the caller's buffer. One generator per thread (own PRNG); no allocation after construction.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

#include "codec/bytes.hpp"
#include "codec/limits.hpp"
#include "codec/mbap.hpp"
#include "load/plan.hpp"
#include "load/request_info.hpp"
#include "load/rng.hpp"
#include "load/zipf.hpp"

namespace mbstorm::load {

// Largest ADU (MBAP header included) an operation can produce.
std::size_t max_request_size(const Operation& op) noexcept;
std::size_t max_request_size(const std::vector<Operation>& operations) noexcept;

class AddressPicker {
  public:
    AddressPicker() = default;
    explicit AddressPicker(const Operation& op) noexcept;
    // Sequential inline (once per request on the engine's hot path), the draws out of line.
    std::uint16_t next(Rng& rng) noexcept {
        if (mode_ != AddressMode::Sequential) return draw(rng);
        const std::uint32_t offset = cursor_;
        // Step by the block size so consecutive requests tile the range; wrap to the first
        // address when the next block would leave it.
        cursor_ += stride_;
        if (cursor_ >= positions_) cursor_ = 0;
        return static_cast<std::uint16_t>(first_ + offset);
    }

  private:
    std::uint16_t draw(Rng& rng) noexcept;  // Uniform and Zipf

    AddressMode mode_ = AddressMode::Sequential;
    std::uint16_t first_ = 0;
    std::uint32_t positions_ = 1;  // usable start addresses: first_ .. first_ + positions_ - 1
    std::uint32_t stride_ = 1;     // sequential: the block size, so blocks tile the range
    std::uint32_t cursor_ = 0;     // sequential: offset of the next start
    ZipfSampler zipf_;
};

class ValuePicker {
  public:
    ValuePicker() = default;
    explicit ValuePicker(const ValueSpec& spec) : spec_(&spec), counter_(spec.value) {}
    std::uint16_t next(Rng& rng) noexcept;
    // Coils: on/off from the next value (Constant/Pattern: value != 0; Counter/Random: low bit).
    bool next_bit(Rng& rng) noexcept;

  private:
    const ValueSpec* spec_ = nullptr;
    std::uint16_t counter_ = 0;
    std::size_t pattern_index_ = 0;
};

class OperationGenerator {
  public:
    // `operations` must outlive the generator and be valid (validate_plan()).
    OperationGenerator(const std::vector<Operation>& operations, std::uint64_t seed);

    // Encodes the next request ADU with `transaction_id` into `out`. Returns the ADU size, or 0
    // when `out` is too small or the codec refused (never happens for a validated plan).
    // One FC01-04 operation, the plan of most load tests, is written inline here.
    std::size_t next(std::uint16_t transaction_id, codec::MutableBytes out,
                     RequestInfo& info) noexcept {
        if (single_read_) return write_read(state_.front(), transaction_id, out, info);
        return next_of_many(transaction_id, out, info);
    }

    // Picks an operation index by weight (exposed for tests).
    std::uint16_t pick_operation() noexcept;

    Rng& rng() noexcept { return rng_; }

  private:
    struct OpState {
        AddressPicker address;
        ValuePicker values;
        std::size_t max_size = 0;  // max_request_size(op), precomputed for the hot path
        // FC01-04: the whole request with transaction id and address 0, which write_read()
        // copies and completes, and its RequestInfo but for the address; empty for the other
        // functions.
        std::array<std::uint8_t, 12> read_frame{};
        RequestInfo read_info;
        bool read = false;
    };

    std::size_t next_of_many(std::uint16_t transaction_id, codec::MutableBytes out,
                             RequestInfo& info) noexcept;

    // FC01-04, the request of most load tests: the 12 bytes written in place from the
    // operation's template, the same bytes the checked encoders give (the plan's checks
    // already hold for these fields).
    std::size_t write_read(OpState& st, std::uint16_t transaction_id, codec::MutableBytes out,
                           RequestInfo& info) noexcept {
        if (out.size() < st.read_frame.size()) return 0;
        info = st.read_info;
        info.address = st.address.next(rng_);
        std::uint8_t* p = out.data();
        std::memcpy(p, st.read_frame.data(), st.read_frame.size());
        codec::store_be16(p, transaction_id);
        codec::store_be16(p + codec::limits::kMbapHeader + 1, info.address);
        return st.read_frame.size();
    }

    std::size_t encode(std::uint16_t op_index, std::uint16_t transaction_id,
                       codec::MutableBytes out, RequestInfo& info) noexcept;

    const std::vector<Operation>& operations_;
    std::vector<std::uint64_t> cumulative_weight_;
    std::vector<OpState> state_;
    bool single_read_ = false;  // the plan is one FC01-04 operation
    Rng rng_;
    std::array<std::uint8_t, codec::limits::kMaxPdu> payload_{};
};

}  // namespace mbstorm::load
