#include "slave/data_model.hpp"

#include <algorithm>
#include <cstring>
#include <stdexcept>
#include <utility>

#include "codec/bytes.hpp"
#include "codec/limits.hpp"

namespace mbstorm::slave {

const char* table_name(Table t) noexcept {
    switch (t) {
        case Table::Coils:
            return "coils";
        case Table::DiscreteInputs:
            return "discrete_inputs";
        case Table::InputRegisters:
            return "input_registers";
        case Table::HoldingRegisters:
            return "holding_registers";
    }
    return "?";
}

std::uint32_t TableSizes::of(Table t) const noexcept {
    switch (t) {
        case Table::Coils:
            return coils;
        case Table::DiscreteInputs:
            return discrete_inputs;
        case Table::InputRegisters:
            return input_registers;
        case Table::HoldingRegisters:
            return holding_registers;
    }
    return 0;
}

namespace {
std::uint32_t checked_size(std::uint32_t size) {
    if (size > kFullTable) throw std::invalid_argument("table size above 65536");
    return size;
}
}  // namespace

// ---- BitTable ----

namespace {
constexpr std::uint64_t low_bits(std::uint32_t n) noexcept {
    return n >= 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << n) - 1;
}

// `n` (1..64) bits of a packed LSB-first byte stream starting at bit `offset`; reads only the
// bytes that hold those bits.
std::uint64_t stream_bits(const std::uint8_t* in, std::uint32_t offset, std::uint32_t n) noexcept {
    std::uint64_t value = 0;
    for (std::uint32_t got = 0; got < n;) {
        const std::uint32_t bit = offset + got;
        const std::uint32_t take = std::min(8 - (bit & 7), n - got);
        const std::uint64_t chunk = (in[bit >> 3] >> (bit & 7)) & low_bits(take);
        value |= chunk << got;
        got += take;
    }
    return value;
}
}  // namespace

// std::atomic value-initialises in C++20, so the tables start all zero.
BitTable::BitTable(std::uint32_t size)
    : words_(new std::atomic<std::uint64_t>[checked_size(size) / 64 + 2]()), size_(size) {}

std::uint64_t BitTable::load64(std::uint32_t pos) const noexcept {
    const std::uint32_t word = pos >> 6;
    const std::uint32_t shift = pos & 63;
    std::uint64_t v = words_[word].load(std::memory_order_relaxed) >> shift;
    if (shift != 0) v |= words_[word + 1].load(std::memory_order_relaxed) << (64 - shift);
    return v;
}

void BitTable::read_packed(std::uint16_t address, std::uint16_t quantity,
                           std::uint8_t* out) const noexcept {
    const std::uint32_t bytes = (std::uint32_t{quantity} + 7) / 8;
    for (std::uint32_t first = 0; first < bytes; first += 8) {
        const std::uint64_t v = load64(address + first * 8);
        const std::uint32_t n = std::min<std::uint32_t>(8, bytes - first);
        for (std::uint32_t b = 0; b < n; ++b)
            out[first + b] = static_cast<std::uint8_t>(v >> (8 * b));
    }
    if ((quantity & 7) != 0) out[bytes - 1] &= static_cast<std::uint8_t>(low_bits(quantity & 7));
}

void BitTable::write_packed(std::uint16_t address, std::uint16_t quantity,
                            const std::uint8_t* in) noexcept {
    std::uint32_t pos = address;
    for (std::uint32_t done = 0; done < quantity;) {
        const std::uint32_t shift = pos & 63;
        const std::uint32_t n = std::min<std::uint32_t>(64 - shift, quantity - done);
        const std::uint64_t mask = low_bits(n) << shift;
        const std::uint64_t bits = stream_bits(in, done, n) << shift;
        std::atomic<std::uint64_t>& word = words_[pos >> 6];
        std::uint64_t old = word.load(std::memory_order_relaxed);
        while (!word.compare_exchange_weak(old, (old & ~mask) | (bits & mask),
                                           std::memory_order_relaxed)) {
        }
        pos += n;
        done += n;
    }
}

// ---- RegisterTable ----

RegisterTable::RegisterTable(std::uint32_t size)
    : words_(new std::atomic<std::uint64_t>[(checked_size(size) + 3) / 4 + 1]()), size_(size) {}

std::uint16_t RegisterTable::mask_write(std::uint16_t address, std::uint16_t and_mask,
                                        std::uint16_t or_mask) noexcept {
    return update(address, [and_mask, or_mask](std::uint16_t current) {
        return static_cast<std::uint16_t>((current & and_mask) | (or_mask & ~and_mask));
    });
}

std::uint16_t RegisterTable::add(std::uint16_t address, std::uint16_t delta) noexcept {
    return update(address, [delta](std::uint16_t current) {
        return static_cast<std::uint16_t>(current + delta);
    });
}

void RegisterTable::write_be(std::uint16_t address, std::uint16_t quantity,
                             const std::uint8_t* in) noexcept {
    // A word at a time: a store when all four of its registers are written, otherwise a
    // compare-and-swap that keeps the others.
    std::uint32_t pos = address;
    for (std::uint32_t done = 0; done < quantity;) {
        const unsigned first = pos & 3;
        const std::uint32_t n = std::min<std::uint32_t>(4 - first, quantity - done);
        std::uint64_t mask = 0, bits = 0;
        for (std::uint32_t k = 0; k < n; ++k) {
            std::uint16_t value;  // the request's bytes are wire order, as the table keeps them
            std::memcpy(&value, in + 2 * (done + k), sizeof value);
            const unsigned shift = lane_shift(first + k);
            mask |= std::uint64_t{0xFFFF} << shift;
            bits |= std::uint64_t{value} << shift;
        }
        std::atomic<std::uint64_t>& word = words_[pos >> 2];
        if (n == 4) {
            word.store(bits, std::memory_order_relaxed);
        } else {
            std::uint64_t old = word.load(std::memory_order_relaxed);
            while (
                !word.compare_exchange_weak(old, (old & ~mask) | bits, std::memory_order_relaxed)) {
            }
        }
        pos += n;
        done += n;
    }
}

void RegisterTable::add_read_counter(std::uint16_t address, std::uint16_t step) {
    if (address >= size_) throw std::out_of_range("read counter address outside the table");
    auto pos =
        std::lower_bound(read_counters_.begin(), read_counters_.end(), address,
                         [](const ReadCounter& c, std::uint16_t a) { return c.address < a; });
    if (pos != read_counters_.end() && pos->address == address) {
        pos->step = step;
    } else {
        read_counters_.insert(pos, ReadCounter{address, step});
    }
    has_read_counters_ = true;
}

void RegisterTable::bump_read_counters(std::uint16_t address, std::uint16_t quantity) noexcept {
    const std::uint32_t end = std::uint32_t{address} + quantity;
    auto it = std::lower_bound(read_counters_.begin(), read_counters_.end(), address,
                               [](const ReadCounter& c, std::uint16_t a) { return c.address < a; });
    for (; it != read_counters_.end() && it->address < end; ++it) {
        add(it->address, it->step);
    }
}

// ---- FileStore ----

FileStore::FileStore(std::uint16_t file_count, std::uint16_t records)
    : data_(new std::atomic<std::uint16_t>[std::max<std::size_t>(
          1, std::size_t{file_count} * records)]()),
      file_count_(file_count),
      records_(records) {}

void FileStore::read_be(std::uint16_t file, std::uint16_t record, std::uint16_t length,
                        std::uint8_t* out) const noexcept {
    const std::atomic<std::uint16_t>* src = data_.get() + index(file, record);
    for (std::uint32_t i = 0; i < length; ++i) {
        codec::store_be16(out + 2 * i, src[i].load(std::memory_order_relaxed));
    }
}

void FileStore::write_be(std::uint16_t file, std::uint16_t record, std::uint16_t length,
                         const std::uint8_t* in) noexcept {
    std::atomic<std::uint16_t>* dst = data_.get() + index(file, record);
    for (std::uint32_t i = 0; i < length; ++i) {
        dst[i].store(codec::load_be16(in + 2 * i), std::memory_order_relaxed);
    }
}

// ---- Diagnostics ----

std::uint16_t Diagnostics::comm_event_count() const noexcept {
    return static_cast<std::uint16_t>(message_count() - exception_count() -
                                      since_clear(fetches_, base_fetches_));
}

void Diagnostics::note_messages(std::uint64_t count, std::uint8_t receive_event,
                                std::uint8_t send_event) noexcept {
    const std::uint64_t first = messages_.fetch_add(count, std::memory_order_relaxed);
    const auto pair = static_cast<std::uint16_t>((unsigned{receive_event} << 8) | send_event);
    // Only the newest kLogPairs survive (older ones would be overwritten at once): from the
    // oldest of those to the end of the ring, then from its start.
    const std::size_t n = count < kLogPairs ? static_cast<std::size_t>(count) : kLogPairs;
    const auto from = static_cast<std::size_t>((first + count - n) % kLogPairs);
    const std::size_t to_end = std::min(n, kLogPairs - from);
    for (std::size_t i = from; i != from + to_end; ++i)
        log_[i].store(pair, std::memory_order_relaxed);
    for (std::size_t i = 0; i != n - to_end; ++i) log_[i].store(pair, std::memory_order_relaxed);
}

void Diagnostics::clear_counters() noexcept {
    auto reset = [](const std::atomic<std::uint64_t>& raw, std::atomic<std::uint64_t>& base) {
        base.store(raw.load(std::memory_order_relaxed), std::memory_order_relaxed);
    };
    reset(messages_, base_messages_);
    reset(exceptions_, base_exceptions_);
    reset(fetches_, base_fetches_);
    reset(no_responses_, base_no_responses_);
    reset(comm_errors_, base_comm_errors_);
    reset(busy_, base_busy_);
}

void Diagnostics::clear_event_log() noexcept {
    base_log_.store(messages_.load(std::memory_order_relaxed), std::memory_order_relaxed);
}

std::size_t Diagnostics::read_event_log(std::uint64_t current_seq,
                                        std::uint8_t* out) const noexcept {
    const std::uint64_t base = base_log_.load(std::memory_order_relaxed);
    std::size_t n = 0;
    // Entries strictly before the current request, newest first: its send event, then receive.
    for (std::uint64_t seq = current_seq; seq > base && n + 2 <= 2 * kLogPairs; --seq) {
        const std::uint16_t pair = log_[(seq - 1) % kLogPairs].load(std::memory_order_relaxed);
        const auto send = static_cast<std::uint8_t>(pair);
        // A send event of 0 means "none" (broadcast): send events always have bit 6 set.
        if (send != 0) out[n++] = send;
        out[n++] = static_cast<std::uint8_t>(pair >> 8);
        if (current_seq - seq + 1 >= kLogPairs) break;
    }
    return n;
}

// ---- DeviceIdentity ----

DeviceIdentity::DeviceIdentity() {
    objects_[kVendorName] = "mbstorm";
    objects_[kProductCode] = "MBSTORM-SLAVE";
    objects_[kMajorMinorRevision] = "0.1";
    objects_[kVendorUrl] = "https://example.invalid/mbstorm";  // placeholder: configure your own
    objects_[kProductName] = "mbstorm reference slave";
    objects_[kModelName] = "reference";
    objects_[kUserApplicationName] = "mbstorm serve";
}

bool DeviceIdentity::set(std::uint8_t id, std::string value) {
    if ((id > kUserApplicationName && id < 0x80) || value.size() > kMaxObjectLength) return false;
    objects_[id] = std::move(value);
    return true;
}

std::uint8_t DeviceIdentity::conformity_level() const noexcept {
    for (unsigned id = 0x80; id <= 0xFF; ++id) {
        if (!objects_[id].empty()) return 0x83;
    }
    for (unsigned id = kVendorUrl; id <= kUserApplicationName; ++id) {
        if (!objects_[id].empty()) return 0x82;
    }
    return 0x81;
}

// ---- DataModel ----

DataModel::DataModel(const ModelConfig& config)
    : coils_(config.sizes.coils),
      discrete_inputs_(config.sizes.discrete_inputs),
      input_registers_(config.sizes.input_registers),
      holding_registers_(config.sizes.holding_registers),
      files_(config.file_count, config.file_records),
      exception_status_(config.exception_status),
      server_id_(config.server_id),
      run_indicator_on_(config.run_indicator_on),
      identity_(config.identity),
      track_diagnostics_(config.track_diagnostics) {
    // FC11 response: byte count, id bytes, run indicator must fit in one PDU.
    if (server_id_.size() > codec::limits::kMaxPdu - 3) {
        throw std::invalid_argument("server id longer than 250 bytes");
    }
}

std::uint32_t DataModel::table_size(Table t) const noexcept {
    switch (t) {
        case Table::Coils:
            return coils_.size();
        case Table::DiscreteInputs:
            return discrete_inputs_.size();
        case Table::InputRegisters:
            return input_registers_.size();
        case Table::HoldingRegisters:
            return holding_registers_.size();
    }
    return 0;
}

bool DataModel::fifo_set(std::uint16_t pointer, std::span<const std::uint16_t> values) noexcept {
    if (values.size() > codec::limits::kMaxFifoCount ||
        !holding_registers_.contains(pointer, 1 + static_cast<std::uint32_t>(values.size()))) {
        return false;
    }
    for (std::size_t i = 0; i < values.size(); ++i) {
        holding_registers_.set(static_cast<std::uint16_t>(pointer + 1 + i), values[i]);
    }
    holding_registers_.set(pointer, static_cast<std::uint16_t>(values.size()));
    return true;
}

bool DataModel::fifo_push(std::uint16_t pointer, std::uint16_t value) noexcept {
    if (!holding_registers_.contains(pointer, 1)) return false;
    const std::uint16_t count = holding_registers_.get(pointer);
    if (count >= codec::limits::kMaxFifoCount ||
        !holding_registers_.contains(pointer, std::uint32_t{count} + 2)) {
        return false;
    }
    holding_registers_.set(static_cast<std::uint16_t>(pointer + 1 + count), value);
    holding_registers_.set(pointer, static_cast<std::uint16_t>(count + 1));
    return true;
}

// ---- UnitModels ----

UnitModels UnitModels::shared(const ModelConfig& config) {
    UnitModels units;
    units.shared_ = true;
    units.owned_.push_back(std::make_unique<DataModel>(config));
    units.by_unit_.fill(units.owned_.front().get());
    return units;
}

UnitModels UnitModels::per_unit(const ModelConfig& config, std::span<const std::uint8_t> ids) {
    UnitModels units;
    std::vector<std::uint8_t> sorted(ids.begin(), ids.end());
    std::sort(sorted.begin(), sorted.end());
    sorted.erase(std::unique(sorted.begin(), sorted.end()), sorted.end());
    for (std::uint8_t id : sorted) {
        units.owned_.push_back(std::make_unique<DataModel>(config));
        units.by_unit_[id] = units.owned_.back().get();
    }
    units.units_ = std::move(sorted);
    return units;
}

}  // namespace mbstorm::slave
