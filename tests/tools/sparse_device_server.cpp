// The second multi-fault target of the fuzzer's tests: a Modbus TCP device with its own small
// sparse map (not the reference slave's 65,536-entry model) and many planted bugs at once.
// The device answers unit ids 1 and 255 (others: no answer) and implements FC 01, 02, 03, 04,
// 05, 06, 0F, 10, 16 and 17 (any other: exception 01; a PDU of the wrong length for its function
// code: exception 03) over this map:
//   holding registers 1000-1039 and 1060-1099 (a hole at 1040-1059), register a holds a;
//   input registers 3000-3015, register a holds 0x1000 + (a - 3000);
//   coils 200-263, even addresses on; discrete inputs 500-531, all on.
// Like libmodbus, after an exception 01 or 03 it sleeps 100 ms (the whole server) and discards
// the connection's unread input. Protocol id != 0: dropped; MBAP length < 2 or > 254: closed.
// The planted bugs (13):
//   1. crash: FC 10 inside the map with byte count != 2 * quantity aborts (inside the map the
//      byte count is trusted; outside it, it is checked and owed 03 as it should be)
//   2. crash: FC 0F inside the coil map with byte count != ceil(quantity / 8) aborts
//   3. crash: FC 17 with a valid read range and a write range that starts in a holding block
//      but runs past its end aborts (only the write start is checked)
//   4. crash: FC 04 with address + quantity == 3017 passes the off-by-one end check and aborts
//   5. wrong value: FC 16 stores (current AND and) OR or, not (current AND and) OR (or AND NOT
//      and); the echo is normal
//   6. stateful: FC 06 writes to 1060-1069 stay in a per-connection cache: other connections
//      (and later ones) read the old value
//   7. silent deviation: FC 06 writing 8000 to 1060 is answered with an echo of value 0000
//      and nothing is stored (a value the device drops on one register)
//   8. whole-server hang: a partial MBAP header (1-6 bytes) idle for 100 ms is finished with a
//      blocking read of up to 3 s, stalling every other client
//   9. crash: accepting a 1,025th concurrent connection aborts (select()'s FD_SET overflow)
//  10. deviation: FC 03 whose start and end are in the holding map but which spans the hole is
//      answered (the hole reads 0) instead of exception 02
//  11. malformed response: FC 02 with a quantity that is a multiple of 8 gets one extra data
//      byte (byte count quantity / 8 + 1)
//  12. one request hangs: FC 10 writing exactly the first block (1000, 40 registers) is never
//      answered (nor stored); the connection goes on
//  13. crash: FC 01 reading 30 coils from 4D2A aborts (a test hook left in, outside the map).
//      One address and one quantity (1 in 2^27 for a guess, neither a boundary nor a map edge):
//      the black-box mode does not find it; coverage mode reads both constants from the
//      device's comparisons (tests/scripts/fuzz_coverage_multi_fault.sh)
// Usage as broken_server_common.hpp (--port, --respawn, --restart-delay-ms, --pid-file,
// --exit-after-s).
#include <array>
#include <chrono>
#include <optional>
#include <span>
#include <thread>

#include "broken_server_common.hpp"

namespace {

using mbstorm::codec::load_be16;
using mbstorm::codec::store_be16;
using Clock = std::chrono::steady_clock;
using Pdu = std::vector<std::uint8_t>;  // a response PDU; empty: no answer

constexpr std::size_t kFdSetSize = 1024;  // bug 9
constexpr auto kExceptionPause = std::chrono::milliseconds(100);
constexpr auto kPartialHeaderIdle = std::chrono::milliseconds(100);  // bug 8
constexpr auto kBlockingReadLimit = std::chrono::seconds(3);         // bug 8

struct Block {
    int first;
    int count;
    int end() const { return first + count; }  // one past the last address
};

constexpr Block kHolding[] = {{1000, 40}, {1060, 40}};
constexpr Block kInput[] = {{3000, 16}};
constexpr Block kCoils[] = {{200, 64}};
constexpr Block kDiscrete[] = {{500, 32}};
constexpr int kHoldingBase = 1000, kCachedFirst = 1060, kCachedCount = 10;  // bug 6

struct Device {
    std::array<std::uint16_t, 100> holding{};  // 1000-1099; the hole's entries stay 0
    std::array<std::uint16_t, 16> input{};
    std::array<bool, 64> coils{};
    std::array<bool, 32> discrete{};
};

struct Conn {
    int fd = -1;
    std::vector<std::uint8_t> in;
    Clock::time_point last_rx = Clock::now();
    std::array<std::optional<std::uint16_t>, kCachedCount> cached;  // bug 6
};

Device initial_device() {
    Device d;
    for (int a = 1000; a < 1100; ++a)
        if (a < 1040 || a >= 1060) d.holding[a - kHoldingBase] = static_cast<std::uint16_t>(a);
    for (int i = 0; i < 16; ++i) d.input[i] = static_cast<std::uint16_t>(0x1000 + i);
    for (int i = 0; i < 64; ++i) d.coils[i] = (200 + i) % 2 == 0;
    d.discrete.fill(true);
    return d;
}

const Block* block_of(std::span<const Block> table, int address) {
    for (const Block& b : table)
        if (address >= b.first && address < b.end()) return &b;
    return nullptr;
}

// A range is served only when it lies wholly inside one contiguous block.
bool inside_one_block(std::span<const Block> table, int address, int quantity) {
    const Block* b = block_of(table, address);
    return b && address + quantity <= b->end();
}

Pdu exception(std::uint8_t fc, std::uint8_t code) {
    return {static_cast<std::uint8_t>(fc | 0x80), code};
}

Pdu echo(const std::uint8_t* p, std::size_t n) {
    return {p, p + n};
}

bool in_cache_range(int address) {
    return address >= kCachedFirst && address < kCachedFirst + kCachedCount;
}

// A holding register as this connection sees it (its own cached FC 06 writes, bug 6).
std::uint16_t read_holding(const Device& d, const Conn& c, int address) {
    if (in_cache_range(address) && c.cached[address - kCachedFirst])
        return *c.cached[address - kCachedFirst];
    return d.holding[address - kHoldingBase];
}

// Writes other than FC 06 go to the store; the writer then sees them, not its stale cache.
void write_holding(Device& d, Conn& c, int address, std::uint16_t value) {
    d.holding[address - kHoldingBase] = value;
    if (in_cache_range(address)) c.cached[address - kCachedFirst].reset();
}

Pdu bits_reply(std::uint8_t fc, const bool* bits, int quantity, int extra_bytes) {
    const int count = (quantity + 7) / 8 + extra_bytes;
    Pdu r = {fc, static_cast<std::uint8_t>(count)};
    r.resize(2 + static_cast<std::size_t>(count), 0);
    for (int i = 0; i < quantity; ++i)
        if (bits[i]) r[2 + i / 8] |= static_cast<std::uint8_t>(1 << (i % 8));
    return r;
}

Pdu read_bits(const std::uint8_t* p, std::size_t n, const Device& d) {
    const std::uint8_t fc = p[0];
    if (n != 5) return exception(fc, 0x03);
    const int address = load_be16(p + 1), quantity = load_be16(p + 3);
    if (fc == 0x01 && address == 0x4D2A && quantity == 30) std::abort();  // bug 13
    if (quantity < 1 || quantity > 2000) return exception(fc, 0x03);
    const std::span<const Block> table = fc == 0x01 ? kCoils : kDiscrete;
    if (!inside_one_block(table, address, quantity)) return exception(fc, 0x02);
    if (fc == 0x01) return bits_reply(fc, &d.coils[address - 200], quantity, 0);
    // Bug 11: the byte count is computed as q / 8 + 1, one too many when q is a multiple of 8.
    return bits_reply(fc, &d.discrete[address - 500], quantity, quantity % 8 == 0 ? 1 : 0);
}

Pdu registers_reply(std::uint8_t fc, int quantity, auto&& value_at) {
    Pdu r = {fc, static_cast<std::uint8_t>(2 * quantity)};
    r.resize(2 + 2 * static_cast<std::size_t>(quantity));
    for (int i = 0; i < quantity; ++i) store_be16(r.data() + 2 + 2 * i, value_at(i));
    return r;
}

Pdu read_holding_registers(const std::uint8_t* p, std::size_t n, const Device& d, const Conn& c) {
    if (n != 5) return exception(0x03, 0x03);
    const int address = load_be16(p + 1), quantity = load_be16(p + 3);
    if (quantity < 1 || quantity > 125) return exception(0x03, 0x03);
    // Bug 10: only the first and last address are looked up, so a range across the hole passes.
    if (!block_of(kHolding, address) || !block_of(kHolding, address + quantity - 1))
        return exception(0x03, 0x02);
    return registers_reply(0x03, quantity, [&](int i) {
        const int a = address + i;
        return block_of(kHolding, a) ? read_holding(d, c, a) : std::uint16_t{0};
    });
}

Pdu read_input_registers(const std::uint8_t* p, std::size_t n, const Device& d) {
    if (n != 5) return exception(0x04, 0x03);
    const int address = load_be16(p + 1), quantity = load_be16(p + 3);
    if (quantity < 1 || quantity > 125) return exception(0x04, 0x03);
    // Bug 4: the end check is off by one (3017 instead of 3016 is the first address past it).
    if (address < 3000 || address + quantity > 3017) return exception(0x04, 0x02);
    if (address + quantity == 3017) std::abort();  // would read input[16], past the array
    return registers_reply(0x04, quantity, [&](int i) { return d.input[address - 3000 + i]; });
}

Pdu write_single_coil(const std::uint8_t* p, std::size_t n, Device& d) {
    if (n != 5) return exception(0x05, 0x03);
    const int address = load_be16(p + 1), value = load_be16(p + 3);
    if (value != 0x0000 && value != 0xFF00) return exception(0x05, 0x03);
    if (!block_of(kCoils, address)) return exception(0x05, 0x02);
    d.coils[address - 200] = value == 0xFF00;
    return echo(p, n);
}

Pdu write_single_register(const std::uint8_t* p, std::size_t n, Device& d, Conn& c) {
    if (n != 5) return exception(0x06, 0x03);
    const int address = load_be16(p + 1);
    const std::uint16_t value = load_be16(p + 3);
    if (!block_of(kHolding, address)) return exception(0x06, 0x02);
    if (address == 1060 && value == 0x8000) {  // bug 7: echoes 0000, stores nothing
        Pdu wrong = echo(p, n);
        wrong[3] = wrong[4] = 0;
        return wrong;
    }
    if (in_cache_range(address))
        c.cached[address - kCachedFirst] = value;  // bug 6: never reaches the store
    else
        d.holding[address - kHoldingBase] = value;
    return echo(p, n);
}

Pdu write_multiple_coils(const std::uint8_t* p, std::size_t n, Device& d) {
    if (n < 6 || n != 6u + p[5]) return exception(0x0F, 0x03);
    const int address = load_be16(p + 1), quantity = load_be16(p + 3);
    if (quantity < 1 || quantity > 1968) return exception(0x0F, 0x03);
    // Bug 2: outside the map the byte count is checked (03 before 02, as owed); inside it is
    // trusted: a mismatch reads past the data.
    const bool inside = inside_one_block(kCoils, address, quantity);
    if (!inside && p[5] != (quantity + 7) / 8) return exception(0x0F, 0x03);
    if (!inside) return exception(0x0F, 0x02);
    if (p[5] != (quantity + 7) / 8) std::abort();
    for (int i = 0; i < quantity; ++i) d.coils[address - 200 + i] = (p[6 + i / 8] >> (i % 8)) & 1;
    return echo(p, 5);
}

Pdu write_multiple_registers(const std::uint8_t* p, std::size_t n, Device& d, Conn& c) {
    if (n < 6 || n != 6u + p[5]) return exception(0x10, 0x03);
    const int address = load_be16(p + 1), quantity = load_be16(p + 3);
    if (quantity < 1 || quantity > 123) return exception(0x10, 0x03);
    // Bug 1: outside the map the byte count is checked (03 before 02, as owed); inside it is
    // trusted: a mismatch reads past the data.
    const bool inside = inside_one_block(kHolding, address, quantity);
    if (!inside && p[5] != 2 * quantity) return exception(0x10, 0x03);
    if (!inside) return exception(0x10, 0x02);
    if (p[5] != 2 * quantity) std::abort();
    if (address == 1000 && quantity == 40) return {};  // bug 12: the whole first block is lost
    for (int i = 0; i < quantity; ++i) write_holding(d, c, address + i, load_be16(p + 6 + 2 * i));
    return echo(p, 5);
}

Pdu mask_write_register(const std::uint8_t* p, std::size_t n, Device& d, Conn& c) {
    if (n != 7) return exception(0x16, 0x03);
    const int address = load_be16(p + 1);
    if (!block_of(kHolding, address)) return exception(0x16, 0x02);
    const std::uint16_t and_mask = load_be16(p + 3), or_mask = load_be16(p + 5);
    // Bug 5: the OR part is not masked with NOT and_mask.
    const auto value =
        static_cast<std::uint16_t>((read_holding(d, c, address) & and_mask) | or_mask);
    write_holding(d, c, address, value);
    return echo(p, n);
}

Pdu read_write_registers(const std::uint8_t* p, std::size_t n, Device& d, Conn& c) {
    if (n < 10 || n != 10u + p[9]) return exception(0x17, 0x03);
    const int read_address = load_be16(p + 1), read_quantity = load_be16(p + 3);
    const int write_address = load_be16(p + 5), write_quantity = load_be16(p + 7);
    if (read_quantity < 1 || read_quantity > 125 || write_quantity < 1 || write_quantity > 121 ||
        p[9] != 2 * write_quantity)
        return exception(0x17, 0x03);
    if (!inside_one_block(kHolding, read_address, read_quantity)) return exception(0x17, 0x02);
    // Bug 3: the write range is checked by its start only; its end runs off the block.
    const Block* block = block_of(kHolding, write_address);
    if (!block) return exception(0x17, 0x02);
    if (write_address + write_quantity > block->end()) std::abort();
    for (int i = 0; i < write_quantity; ++i)
        write_holding(d, c, write_address + i, load_be16(p + 10 + 2 * i));
    return registers_reply(0x17, read_quantity,
                           [&](int i) { return read_holding(d, c, read_address + i); });
}

Pdu handle_pdu(const std::uint8_t* p, std::size_t n, Device& d, Conn& c) {
    switch (p[0]) {
        case 0x01:
        case 0x02:
            return read_bits(p, n, d);
        case 0x03:
            return read_holding_registers(p, n, d, c);
        case 0x04:
            return read_input_registers(p, n, d);
        case 0x05:
            return write_single_coil(p, n, d);
        case 0x06:
            return write_single_register(p, n, d, c);
        case 0x0F:
            return write_multiple_coils(p, n, d);
        case 0x10:
            return write_multiple_registers(p, n, d, c);
        case 0x16:
            return mask_write_register(p, n, d, c);
        case 0x17:
            return read_write_registers(p, n, d, c);
        default:
            return exception(p[0], 0x01);
    }
}

// libmodbus's error recovery after exception 01 or 03: sleep, then drop the unread input.
void pause_and_flush(int fd) {
    std::this_thread::sleep_for(kExceptionPause);
    std::uint8_t buf[4096];
    while (::recv(fd, buf, sizeof buf, MSG_DONTWAIT) > 0) {
    }
}

void append_adu(std::vector<std::uint8_t>& out, const std::uint8_t* request, const Pdu& pdu) {
    const std::size_t at = out.size();
    out.insert(out.end(), request, request + 7);
    out[at + 2] = out[at + 3] = 0;
    store_be16(out.data() + at + 4, static_cast<std::uint16_t>(pdu.size() + 1));
    out.insert(out.end(), pdu.begin(), pdu.end());
}

// Answers every complete frame in c.in. Returns false when the connection must be closed.
bool serve_frames(Conn& c, Device& d) {
    std::vector<std::uint8_t> out;
    std::size_t pos = 0;
    while (c.in.size() - pos >= 7) {
        const std::uint8_t* adu = c.in.data() + pos;
        const std::uint16_t len = load_be16(adu + 4);
        if (len < 2 || len > 254) return false;
        if (c.in.size() - pos < 6u + len) break;
        pos += 6u + len;
        if (load_be16(adu + 2) != 0 || (adu[6] != 1 && adu[6] != 255)) continue;
        const Pdu pdu = handle_pdu(adu + 7, len - 1u, d, c);
        if (pdu.empty()) continue;
        if ((pdu[0] & 0x80) && (pdu[1] == 0x01 || pdu[1] == 0x03)) {
            broken::send_all(c.fd, out);  // the answers before it are not held back
            out.clear();
            pause_and_flush(c.fd);
            append_adu(out, adu, pdu);
            pos = c.in.size();  // the flush drops the frames already read, too
            break;
        }
        append_adu(out, adu, pdu);
    }
    c.in.erase(c.in.begin(), c.in.begin() + static_cast<std::ptrdiff_t>(pos));
    if (!out.empty()) broken::send_all(c.fd, out);
    return true;
}

bool partial_header(const Conn& c) {
    return !c.in.empty() && c.in.size() < 7;
}

// Bug 8: the rest of a stalled header is read with the whole server waiting for it. Returns
// false (close) when the peer closes or the 3 s run out.
bool finish_header_blocking(Conn& c) {
    const auto until = Clock::now() + kBlockingReadLimit;
    std::uint8_t buf[7];
    while (c.in.size() < 7) {
        const auto left =
            std::chrono::duration_cast<std::chrono::milliseconds>(until - Clock::now()).count();
        if (left <= 0) return false;
        pollfd p{c.fd, POLLIN, 0};
        if (::poll(&p, 1, static_cast<int>(left)) <= 0) continue;
        const ssize_t got = ::recv(c.fd, buf, 7 - c.in.size(), 0);
        if (got == 0 || (got < 0 && errno != EAGAIN && errno != EINTR)) return false;
        if (got > 0) c.in.insert(c.in.end(), buf, buf + got);
    }
    c.last_rx = Clock::now();
    return true;
}

// Until the oldest partial header has been idle long enough to trigger bug 8.
int poll_timeout_ms(const std::vector<Conn>& conns) {
    auto wait = std::chrono::milliseconds(1000);
    const auto now = Clock::now();
    for (const Conn& c : conns) {
        if (!partial_header(c)) continue;
        const auto left =
            std::chrono::ceil<std::chrono::milliseconds>(c.last_rx + kPartialHeaderIdle - now);
        wait = std::min(wait, std::max(left, std::chrono::milliseconds(0)));
    }
    return static_cast<int>(wait.count());
}

void accept_all(int listen_fd, std::vector<Conn>& conns) {
    for (;;) {
        const int fd = ::accept4(listen_fd, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
        if (fd < 0) return;
        // Bug 9: the connection table is an fd_set of FD_SETSIZE entries; one more overflows it.
        if (conns.size() >= kFdSetSize) std::abort();
        int one = 1;
        ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
        conns.push_back(Conn{fd, {}, Clock::now(), {}});
    }
}

// One connection's turn in the loop. Returns false when it must be closed.
bool service(Conn& c, short revents, Device& d) {
    if (revents & (POLLIN | POLLHUP | POLLERR)) {
        std::uint8_t buf[8192];
        const ssize_t n = ::recv(c.fd, buf, sizeof buf, 0);
        if (n == 0 || (n < 0 && errno != EAGAIN && errno != EINTR)) return false;
        if (n > 0) {
            c.in.insert(c.in.end(), buf, buf + n);
            c.last_rx = Clock::now();
            if (!serve_frames(c, d)) return false;
        }
    }
    if (partial_header(c) && Clock::now() - c.last_rx >= kPartialHeaderIdle)
        return finish_header_blocking(c) && serve_frames(c, d);
    return true;
}

int serve_sparse(int listen_fd, const broken::Faults&) {
    Device device = initial_device();
    std::vector<Conn> conns;
    std::vector<pollfd> fds;
    for (;;) {
        fds.assign(1, pollfd{listen_fd, POLLIN, 0});
        for (const Conn& c : conns) fds.push_back(pollfd{c.fd, POLLIN, 0});
        if (::poll(fds.data(), fds.size(), poll_timeout_ms(conns)) < 0 && errno != EINTR) return 1;
        const std::size_t polled = conns.size();
        if (fds[0].revents & POLLIN) accept_all(listen_fd, conns);
        std::vector<Conn> keep;
        keep.reserve(conns.size());
        for (std::size_t i = 0; i < conns.size(); ++i) {
            const short revents = i < polled ? fds[i + 1].revents : 0;
            if (service(conns[i], revents, device))
                keep.push_back(std::move(conns[i]));
            else
                ::close(conns[i].fd);
        }
        conns = std::move(keep);
    }
}

}  // namespace

int main(int argc, char** argv) {
    // Bug 9 needs more than 1,024 descriptors: the soft limit goes up to the hard one.
    rlimit files{};
    if (::getrlimit(RLIMIT_NOFILE, &files) == 0) {
        files.rlim_cur = files.rlim_max;
        ::setrlimit(RLIMIT_NOFILE, &files);
    }
    return broken::main_with(argc, argv, broken::Faults{}, serve_sparse);
}
