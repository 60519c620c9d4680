// The reference slave's data: four Modbus tables, FIFO queues, file records, diagnostics and
// device identification, safe to share between server threads.
//
// Concurrency contract
// - Registers are packed four to an atomic 64-bit word, bits 64 to one (relaxed order). A
//   single-register or single-coil write is atomic (a compare-and-swap on its word, so it never
//   loses a neighbour's write): a reader sees the old or the new value.
// - A multi-register write (FC10, FC17) stores each register atomically, in ascending
//   address order (atomic per word: up to four registers at once), but the block as a whole
//   is NOT atomic: a concurrent reader may see a prefix of the new values and a suffix of the
//   old ones. A read sees each word at one instant. FC0F is atomic per 64-bit word of coils.
// - FC16 (mask write) is a compare-and-swap loop, so concurrent mask writes never lose updates.
// - Configuration (table sizes, identity, server id, read counters) is fixed before serving
//   starts; changing it while handlers run is not supported.
#pragma once

#include <array>
#include <atomic>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace mbstorm::slave {

enum class Table : std::uint8_t { Coils, DiscreteInputs, InputRegisters, HoldingRegisters };

// "coils", "discrete_inputs", "input_registers", "holding_registers".
const char* table_name(Table t) noexcept;
// True for the two 1-bit tables.
constexpr bool is_bit_table(Table t) noexcept {
    return t == Table::Coils || t == Table::DiscreteInputs;
}

inline constexpr std::uint32_t kFullTable = 65536;

struct TableSizes {
    std::uint32_t coils = kFullTable;
    std::uint32_t discrete_inputs = kFullTable;
    std::uint32_t input_registers = kFullTable;
    std::uint32_t holding_registers = kFullTable;

    std::uint32_t of(Table t) const noexcept;
    bool operator==(const TableSizes&) const = default;
};

// One bit table (coils or discrete inputs), packed 64 bits per atomic word: a single-bit write
// is one atomic read-modify-write, a multi-bit write is atomic within each 64-bit word, and a
// read of up to 2000 bits touches at most 33 words.
class BitTable {
  public:
    explicit BitTable(std::uint32_t size);

    std::uint32_t size() const noexcept { return size_; }
    // True when [address, address + quantity) lies inside the table.
    bool contains(std::uint16_t address, std::uint32_t quantity) const noexcept {
        return std::uint32_t{address} + quantity <= size_;
    }
    bool get(std::uint16_t address) const noexcept {
        return (words_[address >> 6].load(std::memory_order_relaxed) >> (address & 63)) & 1;
    }
    // Precondition: address < size().
    void set(std::uint16_t address, bool on) noexcept {
        const std::uint64_t bit = std::uint64_t{1} << (address & 63);
        if (on) {
            words_[address >> 6].fetch_or(bit, std::memory_order_relaxed);
        } else {
            words_[address >> 6].fetch_and(~bit, std::memory_order_relaxed);
        }
    }
    // Packs `quantity` bits, LSB of out[0] first, unused high bits of the last byte zero.
    // Precondition: contains(address, quantity).
    void read_packed(std::uint16_t address, std::uint16_t quantity,
                     std::uint8_t* out) const noexcept;
    // Unpacks `quantity` bits in the same layout. Precondition: contains(address, quantity).
    void write_packed(std::uint16_t address, std::uint16_t quantity,
                      const std::uint8_t* in) noexcept;

  private:
    // 64 bits starting at bit `pos` (bits past the table read as 0).
    std::uint64_t load64(std::uint32_t pos) const noexcept;

    std::unique_ptr<std::atomic<std::uint64_t>[]> words_;  // one spare word for load64
    std::uint32_t size_;
};

// One register table (input or holding registers): registers held four to an atomic 64-bit
// word, each in wire (big-endian) byte order, so the word's bytes in memory are the four
// registers as they go on the wire. A read request copies a word (four registers) per load and
// store, shifted into place; get/set/add/mask_write swap the bytes of their one register, and
// every write of part of a word is a compare-and-swap (a whole word is a store).
class RegisterTable {
  public:
    explicit RegisterTable(std::uint32_t size);

    std::uint32_t size() const noexcept { return size_; }
    bool contains(std::uint16_t address, std::uint32_t quantity) const noexcept {
        return std::uint32_t{address} + quantity <= size_;
    }
    std::uint16_t get(std::uint16_t address) const noexcept {
        return wire(static_cast<std::uint16_t>(
            words_[address >> 2].load(std::memory_order_relaxed) >> lane_shift(address & 3)));
    }
    void set(std::uint16_t address, std::uint16_t value) noexcept {
        update(address, [value](std::uint16_t) { return value; });
    }
    // Atomically applies (current AND and_mask) OR (or_mask AND NOT and_mask); returns the result.
    std::uint16_t mask_write(std::uint16_t address, std::uint16_t and_mask,
                             std::uint16_t or_mask) noexcept;
    // Atomically adds delta (modulo 2^16); returns the result.
    std::uint16_t add(std::uint16_t address, std::uint16_t delta) noexcept;

    // Copies registers to `out` big-endian, first bumping any read counter in range. Writes
    // exactly 2 * quantity bytes. Precondition: contains(address, quantity).
    // Inline, four registers per 8-byte store: two neighbouring words funnelled into the four
    // registers from `address` on (as a called loop of byte stores it was a fifth of the
    // slave's instructions at FC03 x 10; as a 16-bit load and store per register, 4.5 a
    // register).
    [[gnu::always_inline]] void read_be(std::uint16_t address, std::uint16_t quantity,
                                        std::uint8_t* out) noexcept {
        if (has_read_counters_) bump_read_counters(address, quantity);
        if constexpr (std::endian::native != std::endian::little) {
            for (std::uint32_t i = 0; i < quantity; ++i) {
                const std::uint16_t value = wire(get(static_cast<std::uint16_t>(address + i)));
                std::memcpy(out + 2 * i, &value, sizeof value);
            }
            return;
        }
        const std::atomic<std::uint64_t>* word = words_.get() + (address >> 2);
        const unsigned shift = 16 * (address & 3u);
        // `ahead` holds the registers not yet copied from the current word, lowest first; the
        // next word's first registers fill its top. (x << 1) << (63 - shift) is x << (64 -
        // shift) that gives 0 for shift 0 instead of undefined behaviour. The look-ahead may
        // read the spare word past the table's last one (zero, never written).
        std::uint64_t ahead = word->load(std::memory_order_relaxed) >> shift;
        const std::uint8_t* const rounds_end = out + 2 * (quantity & ~3u);
        for (; out != rounds_end; out += 8) {
            const std::uint64_t next = (++word)->load(std::memory_order_relaxed);
            const std::uint64_t four = ahead | ((next << 1) << (63 - shift));
            std::memcpy(out, &four, sizeof four);
            ahead = next >> shift;
        }
        if ((quantity & 3u) == 0) return;
        std::uint64_t rest =
            ahead | ((word[1].load(std::memory_order_relaxed) << 1) << (63 - shift));
        if (quantity & 2u) {
            const auto two = static_cast<std::uint32_t>(rest);
            std::memcpy(out, &two, sizeof two);
            out += 4;
            rest >>= 32;
        }
        if (quantity & 1u) {
            const auto one = static_cast<std::uint16_t>(rest);
            std::memcpy(out, &one, sizeof one);
        }
    }
    // read_be by whole words: one 8-byte load and store per word the range touches, no
    // shifts, and in exchange up to kWordSlack bytes before `out` and after out + 2 * quantity
    // are overwritten (with neighbouring registers). Precondition: contains(address, quantity),
    // and [out - kWordSlack, out + 2 * quantity + kWordSlack) is writable and the caller
    // writes what it needs outside [out, out + 2 * quantity) afterwards.
    static constexpr std::size_t kWordSlack = 6;
    [[gnu::always_inline]] void read_be_words(std::uint16_t address, std::uint16_t quantity,
                                              std::uint8_t* out) noexcept {
        if (has_read_counters_) bump_read_counters(address, quantity);
        const std::atomic<std::uint64_t>* word = words_.get() + (address >> 2);
        const std::atomic<std::uint64_t>* const last =
            words_.get() + ((std::uint32_t{address} + quantity - 1) >> 2);
        out -= 2 * (address & 3u);
        for (;; out += 8) {
            const std::uint64_t four = word->load(std::memory_order_relaxed);
            std::memcpy(out, &four, sizeof four);  // the word's bytes are its registers' wire bytes
            if (word++ == last) break;
        }
    }
    // Stores big-endian values from `in`. Precondition: contains(address, quantity).
    void write_be(std::uint16_t address, std::uint16_t quantity, const std::uint8_t* in) noexcept;

    // Configuration: the register at `address` grows by `step` before every read that covers
    // it (so consecutive reads see increasing values). Not thread-safe against readers.
    void add_read_counter(std::uint16_t address, std::uint16_t step);
    bool has_read_counters() const noexcept { return !read_counters_.empty(); }

  private:
    // Host order <-> wire order (its own inverse).
    static constexpr std::uint16_t wire(std::uint16_t v) noexcept {
        if constexpr (std::endian::native == std::endian::little) return __builtin_bswap16(v);
        return v;
    }
    // Where register `lane` (0-3) of a word sits in the word's value, so that the word's
    // bytes in memory are its registers in address order.
    static constexpr unsigned lane_shift(unsigned lane) noexcept {
        if constexpr (std::endian::native == std::endian::little) return 16 * lane;
        return 48 - 16 * lane;
    }
    // Replaces one register by next(current) (host order) with a compare-and-swap on its
    // word, so writes to its neighbours are never lost. Returns the value stored.
    template <class Next>
    std::uint16_t update(std::uint16_t address, Next next) noexcept {
        std::atomic<std::uint64_t>& word = words_[address >> 2];
        const unsigned shift = lane_shift(address & 3);
        const std::uint64_t mask = std::uint64_t{0xFFFF} << shift;
        std::uint64_t old = word.load(std::memory_order_relaxed);
        std::uint16_t value;
        do {
            value = next(wire(static_cast<std::uint16_t>(old >> shift)));
        } while (!word.compare_exchange_weak(
            old, (old & ~mask) | (std::uint64_t{wire(value)} << shift), std::memory_order_relaxed));
        return value;
    }
    struct ReadCounter {
        std::uint16_t address;
        std::uint16_t step;
    };
    void bump_read_counters(std::uint16_t address, std::uint16_t quantity) noexcept;

    // (size + 3) / 4 words and a spare one (always zero) for read_be's look-ahead.
    std::unique_ptr<std::atomic<std::uint64_t>[]> words_;
    std::uint32_t size_;
    std::vector<ReadCounter> read_counters_;  // sorted by address
    bool has_read_counters_ = false;          // !read_counters_.empty(), one load on reads
};

// File records for FC20/21: files 1..file_count, each `records` 16-bit records numbered from 0.
class FileStore {
  public:
    FileStore(std::uint16_t file_count, std::uint16_t records);

    std::uint16_t file_count() const noexcept { return file_count_; }
    std::uint16_t records() const noexcept { return records_; }
    // True when file exists and [record, record + length) lies inside it.
    bool contains(std::uint16_t file, std::uint16_t record, std::uint32_t length) const noexcept {
        return file >= 1 && file <= file_count_ && std::uint32_t{record} + length <= records_;
    }
    std::uint16_t get(std::uint16_t file, std::uint16_t record) const noexcept {
        return data_[index(file, record)].load(std::memory_order_relaxed);
    }
    void set(std::uint16_t file, std::uint16_t record, std::uint16_t value) noexcept {
        data_[index(file, record)].store(value, std::memory_order_relaxed);
    }
    // Preconditions: contains(file, record, length).
    void read_be(std::uint16_t file, std::uint16_t record, std::uint16_t length,
                 std::uint8_t* out) const noexcept;
    void write_be(std::uint16_t file, std::uint16_t record, std::uint16_t length,
                  const std::uint8_t* in) noexcept;

  private:
    std::size_t index(std::uint16_t file, std::uint16_t record) const noexcept {
        return static_cast<std::size_t>(file - 1) * records_ + record;
    }
    std::unique_ptr<std::atomic<std::uint16_t>[]> data_;
    std::uint16_t file_count_;
    std::uint16_t records_;
};

// Serial-line diagnostics (FC08 counters, FC0B comm event counter, FC0C event log), kept
// cheaply: the handler does one atomic increment per request (a server counts the FC03/04
// reads it answers inline and adds them per frame loop: note_messages); every reported counter
// is a raw monotonic count minus the value it had at the last clear.
//
// Definitions over TCP (there is no shared bus, so "bus" and "server" counts coincide):
//   bus/server message count   every request handled for this model (including the current one)
//   bus exception error count  exception responses sent (by the handler, or noted by the server)
//   comm event counter (FC0B)  messages - exceptions - FC0B/FC0C requests (fetches change nothing)
//   server no response count   requests answered with silence (broadcasts, noted drops)
//   bus communication errors   framing errors the server notes; busy count: 06s the server notes
//   NAK and character overrun  always 0
// The event log holds the last 32 requests as (receive event, send event) pairs; under
// concurrency an entry still being written by another thread may show its previous content.
class Diagnostics {
  public:
    // The handler's per-request bookkeeping. Returns the request's sequence number.
    std::uint64_t begin_message() noexcept {
        return messages_.fetch_add(1, std::memory_order_relaxed);
    }
    void end_message(std::uint64_t seq, std::uint8_t receive_event,
                     std::uint8_t send_event) noexcept {
        log_[seq % kLogPairs].store(
            static_cast<std::uint16_t>((unsigned{receive_event} << 8) | send_event),
            std::memory_order_relaxed);
    }
    // `count` requests handled normally, all with the same events, as if each had been
    // begun and ended in turn: one atomic add for the lot (a locked increment per request was
    // half of an FC03's handler time) and the log's last min(count, kLogPairs) entries.
    void note_messages(std::uint64_t count, std::uint8_t receive_event,
                       std::uint8_t send_event) noexcept;
    void note_exception() noexcept { exceptions_.fetch_add(1, std::memory_order_relaxed); }
    void note_fetch() noexcept { fetches_.fetch_add(1, std::memory_order_relaxed); }
    void note_no_response() noexcept { no_responses_.fetch_add(1, std::memory_order_relaxed); }
    void note_comm_error() noexcept { comm_errors_.fetch_add(1, std::memory_order_relaxed); }
    void note_busy() noexcept { busy_.fetch_add(1, std::memory_order_relaxed); }

    std::uint16_t message_count() const noexcept { return since_clear(messages_, base_messages_); }
    std::uint16_t exception_count() const noexcept {
        return since_clear(exceptions_, base_exceptions_);
    }
    std::uint16_t no_response_count() const noexcept {
        return since_clear(no_responses_, base_no_responses_);
    }
    std::uint16_t comm_error_count() const noexcept {
        return since_clear(comm_errors_, base_comm_errors_);
    }
    std::uint16_t busy_count() const noexcept { return since_clear(busy_, base_busy_); }
    std::uint16_t comm_event_count() const noexcept;

    // FC08/0A (and FC08/01): every counter back to 0.
    void clear_counters() noexcept;
    // FC08/01 with 0xFF00: the event log restarts empty.
    void clear_event_log() noexcept;

    // Writes up to 64 event bytes, most recent first, excluding request `current_seq` itself.
    std::size_t read_event_log(std::uint64_t current_seq, std::uint8_t* out) const noexcept;

    static constexpr std::size_t kLogPairs = 32;

  private:
    static std::uint16_t since_clear(const std::atomic<std::uint64_t>& raw,
                                     const std::atomic<std::uint64_t>& base) noexcept {
        return static_cast<std::uint16_t>(raw.load(std::memory_order_relaxed) -
                                          base.load(std::memory_order_relaxed));
    }

    std::atomic<std::uint64_t> messages_{0}, exceptions_{0}, fetches_{0}, no_responses_{0},
        comm_errors_{0}, busy_{0};
    std::atomic<std::uint64_t> base_messages_{0}, base_exceptions_{0}, base_fetches_{0},
        base_no_responses_{0}, base_comm_errors_{0}, base_busy_{0}, base_log_{0};
    std::array<std::atomic<std::uint16_t>, kLogPairs> log_{};  // receive << 8 | send
};

// Device identification objects for FC2B/0E. Ids 0x00-0x02 are basic (always present),
// 0x03-0x06 regular, 0x80-0xFF extended; regular and extended objects are present when
// non-empty. Values longer than kMaxObjectLength cannot be served and are rejected by set().
class DeviceIdentity {
  public:
    static constexpr std::size_t kMaxObjectLength = 244;  // 253 - 7 header - 2 (id, length)
    enum : std::uint8_t {
        kVendorName = 0x00,
        kProductCode = 0x01,
        kMajorMinorRevision = 0x02,
        kVendorUrl = 0x03,
        kProductName = 0x04,
        kModelName = 0x05,
        kUserApplicationName = 0x06,
    };

    DeviceIdentity();  // mbstorm defaults for the seven standard objects
    bool operator==(const DeviceIdentity&) const = default;

    // False (and nothing changes) for ids 0x07-0x7F or values over kMaxObjectLength.
    bool set(std::uint8_t id, std::string value);
    const std::string& get(std::uint8_t id) const noexcept { return objects_[id]; }
    bool present(std::uint8_t id) const noexcept { return id <= 0x02 || !objects_[id].empty(); }
    // 0x81 basic, 0x82 regular, 0x83 extended (all with individual access).
    std::uint8_t conformity_level() const noexcept;

  private:
    std::array<std::string, 256> objects_;
};

struct ModelConfig {
    TableSizes sizes;
    std::uint16_t file_count = 4;
    std::uint16_t file_records = 10000;  // spec maximum record number is 9999
    std::uint8_t exception_status = 0;   // FC07
    std::vector<std::uint8_t> server_id = {'m', 'b', 's', 't', 'o', 'r', 'm'};  // FC11
    bool run_indicator_on = true;                                               // FC11
    DeviceIdentity identity;
    bool track_diagnostics = true;  // false: no per-request atomic increments, counters stay 0
    bool operator==(const ModelConfig&) const = default;
};

// FC18 FIFO layout (our convention, the spec leaves it to the device): at pointer address P
// the holding register P holds the FIFO count (0..31) and registers P+1..P+count hold the
// queued values, oldest first. Reading does not consume. A count above 31 answers 03; a queue
// running past the end of the table answers 02. fifo_push/fifo_set help tests and scenarios.
class DataModel {
  public:
    explicit DataModel(const ModelConfig& config = {});
    DataModel(const DataModel&) = delete;
    DataModel& operator=(const DataModel&) = delete;

    BitTable& coils() noexcept { return coils_; }
    BitTable& discrete_inputs() noexcept { return discrete_inputs_; }
    RegisterTable& input_registers() noexcept { return input_registers_; }
    RegisterTable& holding_registers() noexcept { return holding_registers_; }
    const BitTable& coils() const noexcept { return coils_; }
    const BitTable& discrete_inputs() const noexcept { return discrete_inputs_; }
    const RegisterTable& input_registers() const noexcept { return input_registers_; }
    const RegisterTable& holding_registers() const noexcept { return holding_registers_; }
    FileStore& files() noexcept { return files_; }
    Diagnostics& diagnostics() noexcept { return diagnostics_; }

    std::uint32_t table_size(Table t) const noexcept;

    std::uint8_t exception_status() const noexcept {
        return exception_status_.load(std::memory_order_relaxed);
    }
    void set_exception_status(std::uint8_t v) noexcept {
        exception_status_.store(v, std::memory_order_relaxed);
    }
    std::span<const std::uint8_t> server_id() const noexcept { return server_id_; }
    bool run_indicator_on() const noexcept { return run_indicator_on_; }
    const DeviceIdentity& identity() const noexcept { return identity_; }
    bool track_diagnostics() const noexcept { return track_diagnostics_; }

    // Writes a whole FIFO at `pointer` (count + values). False if it would not fit.
    bool fifo_set(std::uint16_t pointer, std::span<const std::uint16_t> values) noexcept;
    // Appends one value; false when the queue is full (31) or would leave the table.
    bool fifo_push(std::uint16_t pointer, std::uint16_t value) noexcept;

  private:
    BitTable coils_;
    BitTable discrete_inputs_;
    RegisterTable input_registers_;
    RegisterTable holding_registers_;
    FileStore files_;
    Diagnostics diagnostics_;
    std::atomic<std::uint8_t> exception_status_;
    std::vector<std::uint8_t> server_id_;
    bool run_indicator_on_;
    DeviceIdentity identity_;
    bool track_diagnostics_;
};

// What to answer for a unit id that has no model (per-unit mode only).
enum class UnknownUnitPolicy : std::uint8_t {
    GatewayTargetFailed,     // exception 0x0B, like a gateway whose target is silent (default)
    GatewayPathUnavailable,  // exception 0x0A
    Ignore,                  // no response at all
};

// Maps unit id -> model. In shared mode every unit id (0 included) gets the same model. Over
// TCP unit 0 is an ordinary address unless `broadcast_unit_zero` is set, in which case a
// unit-0 request is executed on every model and never answered (serial-line semantics).
class UnitModels {
  public:
    static UnitModels shared(const ModelConfig& config = {});
    // One model per listed unit id (duplicates ignored).
    static UnitModels per_unit(const ModelConfig& config, std::span<const std::uint8_t> units);

    UnitModels(UnitModels&&) noexcept = default;
    UnitModels& operator=(UnitModels&&) noexcept = default;

    // nullptr when `unit` has no model.
    DataModel* find(std::uint8_t unit) const noexcept { return by_unit_[unit]; }
    bool is_shared() const noexcept { return shared_; }
    // Each distinct model once, in ascending unit order.
    std::size_t model_count() const noexcept { return owned_.size(); }
    DataModel& model_at(std::size_t i) const noexcept { return *owned_[i]; }
    // The unit ids served (shared mode: empty, meaning all).
    const std::vector<std::uint8_t>& units() const noexcept { return units_; }

    UnknownUnitPolicy unknown_unit_policy = UnknownUnitPolicy::GatewayTargetFailed;
    bool broadcast_unit_zero = false;

  private:
    UnitModels() = default;
    std::array<DataModel*, 256> by_unit_{};
    std::vector<std::unique_ptr<DataModel>> owned_;
    std::vector<std::uint8_t> units_;
    bool shared_ = false;
};

}  // namespace mbstorm::slave
