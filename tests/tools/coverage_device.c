/* A small Modbus TCP device in plain C for the grey-box tests: built by
 * tests/scripts/fuzz_coverage.sh with clang
 * -fsanitize-coverage=trace-pc-guard,trace-cmp,pc-table and mbstorm's runtime
 * (coverage/mbstorm_coverage.c), as a user would build their own server.
 *
 * 1000 holding registers at 0; read (03), write single (06), write multiple (10) and mask
 * write (16), each with the specification's checks (01, 02, 03); pipelined requests are
 * answered in order. Two planted crashes that need values nobody guesses, two fields that must
 * each equal a constant at once:
 *   - write single register: address 0x0123 with value 0x4D42 aborts;
 *   - mask write register: address 0x0042 with AND mask 0x5AA5 and OR mask 0x0F0F writes
 *     through a null pointer.
 * A black-box fuzzer meets them once in 2^32 tries; one that reads the comparisons the device
 * makes passes them one field at a time.
 *
 * Built with pc-table too, for --coverage-report: the request handler (answer) stays a function
 * of its own, which every request reaches; the maintenance routine (clear_registers) runs on
 * SIGUSR1 only, which no request reaches.
 *
 * The same device speaks RTU over TCP (--framing rtu: unit, PDU, CRC-16, as a gateway does) or
 * RTU or ASCII on a serial line (--tty PATH --framing rtu|ascii), unit 1: an RTU frame ends
 * where its function code says or, for a code it does not know, at the line's silence, and a
 * silence of 1 ms inside a frame breaks it (the specification's t1.5 above 19200 baud is
 * 0.75 ms, its t3.5 1.75 ms);
 * an ASCII frame at its LF. A frame whose CRC or LRC is wrong, or for another unit, gets no
 * answer.
 *
 * Usage: coverage_device [--port P] [--framing mbap|rtu|ascii] [--tty PATH]
 *   prints "PORT <n>" once listening (or "TTY" once the line is open); runs until killed. */
#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

enum { kRegisters = 1000, kMaxClients = 1024, kBuffer = 4096 };
enum { kRead = 0x03, kWriteOne = 0x06, kWriteMany = 0x10, kMaskWrite = 0x16 };
enum { kIllegalFunction = 1, kIllegalAddress = 2, kIllegalValue = 3 };
enum framing { kMbap, kRtu, kAscii };
/* A line's silence ends an RTU frame; over TCP, bytes no frame can be cut from (a frame of a
 * code it does not know whose CRC never matches) are dropped after a longer quiet. */
enum { kUnit = 1, kSilenceMs = 1, kTcpQuietMs = 20 };

static uint16_t registers[kRegisters];
static uint16_t* volatile null_register; /* volatile: the compiler may not assume it away */

struct client {
    int fd;
    uint8_t in[kBuffer];
    size_t size;
    long long last_byte_ms; /* RTU over TCP: when its last bytes came */
};

static long long now_ms(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (long long)t.tv_sec * 1000 + t.tv_nsec / 1000000;
}

static uint16_t be16(const uint8_t* p) {
    return (uint16_t)(p[0] << 8 | p[1]);
}
static void put16(uint8_t* p, uint16_t v) {
    p[0] = (uint8_t)(v >> 8);
    p[1] = (uint8_t)v;
}

/* Writes the PDU answer to `out`; returns its size. */
static size_t exception(uint8_t fc, uint8_t code, uint8_t* out) {
    out[0] = (uint8_t)(fc | 0x80);
    out[1] = code;
    return 2;
}

static size_t read_registers(const uint8_t* pdu, size_t n, uint8_t* out) {
    if (n != 5) return exception(pdu[0], kIllegalValue, out);
    const uint16_t start = be16(pdu + 1), count = be16(pdu + 3);
    if (count < 1 || count > 125) return exception(pdu[0], kIllegalValue, out);
    if (start + count > kRegisters) return exception(pdu[0], kIllegalAddress, out);
    out[0] = pdu[0];
    out[1] = (uint8_t)(count * 2);
    for (uint16_t i = 0; i < count; ++i) put16(out + 2 + 2 * i, registers[start + i]);
    return 2 + 2u * count;
}

static size_t write_one(const uint8_t* pdu, size_t n, uint8_t* out) {
    if (n != 5) return exception(pdu[0], kIllegalValue, out);
    const uint16_t address = be16(pdu + 1), value = be16(pdu + 3);
    if (address >= kRegisters) return exception(pdu[0], kIllegalAddress, out);
    if (address == 0x0123 && value == 0x4D42) abort(); /* planted */
    registers[address] = value;
    memcpy(out, pdu, 5);
    return 5;
}

static size_t write_many(const uint8_t* pdu, size_t n, uint8_t* out) {
    if (n < 6) return exception(pdu[0], kIllegalValue, out);
    const uint16_t start = be16(pdu + 1), count = be16(pdu + 3);
    if (count < 1 || count > 123 || pdu[5] != count * 2 || n != 6u + pdu[5])
        return exception(pdu[0], kIllegalValue, out);
    if (start + count > kRegisters) return exception(pdu[0], kIllegalAddress, out);
    for (uint16_t i = 0; i < count; ++i) registers[start + i] = be16(pdu + 6 + 2 * i);
    memcpy(out, pdu, 5);
    return 5;
}

static size_t mask_write(const uint8_t* pdu, size_t n, uint8_t* out) {
    if (n != 7) return exception(pdu[0], kIllegalValue, out);
    const uint16_t address = be16(pdu + 1), and_mask = be16(pdu + 3), or_mask = be16(pdu + 5);
    if (address >= kRegisters) return exception(pdu[0], kIllegalAddress, out);
    uint16_t* target = &registers[address];
    if (address == 0x0042 && and_mask == 0x5AA5 && or_mask == 0x0F0F)
        target = null_register; /* planted */
    *target = (uint16_t)((*target & and_mask) | (or_mask & ~and_mask));
    memcpy(out, pdu, 7);
    return 7;
}

/* noinline: at -O1 it would be part of main, and --coverage-report lists functions. */
__attribute__((noinline)) static size_t answer(const uint8_t* pdu, size_t n, uint8_t* out) {
    switch (pdu[0]) {
        case kRead:
            return read_registers(pdu, n, out);
        case kWriteOne:
            return write_one(pdu, n, out);
        case kWriteMany:
            return write_many(pdu, n, out);
        case kMaskWrite:
            return mask_write(pdu, n, out);
    }
    return exception(pdu[0], kIllegalFunction, out);
}

/* Maintenance, on SIGUSR1: never reached from the network. */
static void clear_registers(int signal_number) {
    (void)signal_number;
    memset(registers, 0, sizeof registers);
}

/* Answers every whole frame in the client's buffer; 0 when the connection must close. */
static int serve(struct client* c) {
    size_t at = 0;
    uint8_t out[kBuffer];
    size_t out_size = 0;
    while (c->size - at >= 7) {
        const uint8_t* h = c->in + at;
        const uint16_t length = be16(h + 4);
        if (length < 2 || length > 254) return 0; /* the stream can no longer be framed */
        if (c->size - at < 6u + length) break;
        if (be16(h + 2) != 0) { /* not Modbus: discarded, as the specification asks */
            at += 6u + length;
            continue;
        }
        uint8_t* rsp = out + out_size;
        const size_t pdu = answer(h + 7, length - 1u, rsp + 7);
        memcpy(rsp, h, 4);
        put16(rsp + 4, (uint16_t)(pdu + 1));
        rsp[6] = h[6];
        out_size += 7 + pdu;
        at += 6u + length;
        if (out_size > sizeof out - 300) { /* no room for another answer: send these first */
            if (send(c->fd, out, out_size, MSG_NOSIGNAL) != (ssize_t)out_size) return 0;
            out_size = 0;
        }
    }
    memmove(c->in, c->in + at, c->size - at);
    c->size -= at;
    return out_size == 0 || send(c->fd, out, out_size, MSG_NOSIGNAL) == (ssize_t)out_size;
}

static uint16_t crc16(const uint8_t* p, size_t n) {
    uint16_t crc = 0xFFFF;
    for (size_t i = 0; i < n; ++i) {
        crc ^= p[i];
        for (int b = 0; b < 8; ++b) crc = (uint16_t)(crc & 1 ? (crc >> 1) ^ 0xA001 : crc >> 1);
    }
    return crc;
}

static uint8_t lrc(const uint8_t* p, size_t n) {
    uint8_t sum = 0;
    for (size_t i = 0; i < n; ++i) sum = (uint8_t)(sum + p[i]);
    return (uint8_t)-sum;
}

/* The answer to the serial-style frame `f` (unit and PDU, checksum already checked) framed for
 * `framing` in `out`; its size, 0 for no answer (another unit). */
static size_t answer_frame(const uint8_t* f, size_t n, enum framing framing, uint8_t* out) {
    if (n < 2 || (f[0] != kUnit && f[0] != 0)) return 0;
    uint8_t adu[1 + 256];
    adu[0] = f[0];
    const size_t size = 1 + answer(f + 1, n - 1, adu + 1);
    if (f[0] == 0) return 0; /* broadcast: carried out, never answered */
    if (framing == kRtu) {
        memcpy(out, adu, size);
        const uint16_t crc = crc16(adu, size);
        out[size] = (uint8_t)crc;
        out[size + 1] = (uint8_t)(crc >> 8);
        return size + 2;
    }
    adu[size] = lrc(adu, size);
    size_t at = 0;
    out[at++] = ':';
    for (size_t i = 0; i <= size; ++i) at += (size_t)sprintf((char*)out + at, "%02X", adu[i]);
    out[at++] = '\r';
    out[at++] = '\n';
    return at;
}

/* RTU: the size of the request frame at `f` (`n` bytes so far), by the specification's length
 * rule for its code (every public code, though it serves four): SIZE_MAX while the code or
 * its byte count has not come yet, 0 for a code with no rule. */
static size_t rtu_size(const uint8_t* f, size_t n) {
    if (n < 2) return SIZE_MAX;
    switch (f[1]) {
        case 0x01:
        case 0x02:
        case 0x03:
        case 0x04:
        case 0x05:
        case 0x06:
        case 0x08:
            return 8;
        case 0x07:
        case 0x0B:
        case 0x0C:
        case 0x11:
            return 4;
        case 0x0F:
        case 0x10:
            return n < 7 ? SIZE_MAX : 9u + f[6];
        case 0x14:
        case 0x15:
            return n < 3 ? SIZE_MAX : 5u + f[2];
        case 0x16:
            return 10;
        case 0x17:
            return n < 11 ? SIZE_MAX : 13u + f[10];
        case 0x18:
            return 6;
        case 0x2B: /* read device identification (MEI 0E); other MEI types have no rule */
            return n < 3 ? SIZE_MAX : f[2] == 0x0E ? 7 : 0;
    }
    return 0; /* no rule: the frame ends at the first CRC that matches, or the silence */
}

/* A frame of a code without a length rule: it ends at the first CRC that matches; on a line
 * that fell silent, at the silence. SIZE_MAX while neither has come. */
static size_t crc_end(const uint8_t* f, size_t n, int silent) {
    for (size_t end = 4; end <= n; ++end)
        if (crc16(f, end - 2) == (uint16_t)(f[end - 2] | f[end - 1] << 8)) return end;
    return silent ? n : SIZE_MAX;
}

static int hex_digit(uint8_t c) {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return -1;
}

/* ASCII: the frame ':' .. LF at the start of the buffer, decoded into `f`; its size, or 0
 * when the frame is bad (it is dropped all the same). */
static size_t ascii_frame(const uint8_t* in, size_t end, uint8_t* f) {
    if (end < 5 || in[end - 2] != '\r' || (end - 3) % 2) return 0;
    size_t n = 0;
    for (size_t i = 1; i + 2 < end; i += 2) {
        const int hi = hex_digit(in[i]), lo = hex_digit(in[i + 1]);
        if (hi < 0 || lo < 0) return 0;
        f[n++] = (uint8_t)(hi << 4 | lo);
    }
    return n >= 3 && lrc(f, n - 1) == f[n - 1] ? n - 1 : 0;
}

/* Serial-style framings: answers every whole frame in the buffer; `silent` says the line has
 * been quiet (what is buffered is all the frame there is). 0 when a write failed. */
static int serve_serial(struct client* c, enum framing framing, int silent) {
    uint8_t out[2 * kBuffer + 8], f[kBuffer];
    for (;;) {
        size_t used = 0, n = 0, size = 0;
        if (framing == kAscii) {
            const uint8_t* colon = memchr(c->in, ':', c->size);
            used = colon ? (size_t)(colon - c->in) : c->size; /* noise before the ':' */
            const uint8_t* lf = colon ? memchr(colon, '\n', c->size - used) : NULL;
            if (lf) {
                const size_t end = (size_t)(lf - colon) + 1;
                n = ascii_frame(colon, end, f);
                used += end;
            }
            if (!lf && !used) return 1;
        } else {
            n = rtu_size(c->in, c->size);
            if (n == 0) n = crc_end(c->in, c->size, silent);
            if (n > c->size) return 1; /* more to come (on a line: dropped at the silence) */
            used = n;
            if (n < 4 || crc16(c->in, n - 2) != (uint16_t)(c->in[n - 2] | c->in[n - 1] << 8))
                n = 0;
            else
                memcpy(f, c->in, n -= 2);
        }
        if (n) size = answer_frame(f, n, framing, out);
        memmove(c->in, c->in + used, c->size - used);
        c->size -= used;
        if (size && write(c->fd, out, size) != (ssize_t)size) return 0;
    }
}

/* A serial line at PATH, raw: 0 on success. */
static int open_line(const char* path, struct client* c) {
    c->fd = open(path, O_RDWR | O_NOCTTY);
    c->size = 0;
    struct termios t;
    if (c->fd < 0 || tcgetattr(c->fd, &t) != 0) return -1;
    cfmakeraw(&t);
    tcsetattr(c->fd, TCSANOW, &t);
    printf("TTY\n");
    fflush(stdout);
    return 0;
}

/* On a serial line: one client, the line; a silence of kSilenceMs ends an RTU frame. */
static int run_line(const char* path, enum framing framing) {
    static struct client line;
    if (open_line(path, &line) != 0) return 1;
    for (;;) {
        struct pollfd p = {line.fd, POLLIN, 0};
        const int ready = poll(&p, 1, line.size ? kSilenceMs : -1);
        if (ready == 0) {
            if (!serve_serial(&line, framing, 1)) return 1;
            line.size = 0; /* what the silence did not make a frame of is dropped */
            continue;
        }
        const ssize_t n = read(line.fd, line.in + line.size, sizeof line.in - line.size);
        if (n > 0) line.size += (size_t)n;
        if (!serve_serial(&line, framing, line.size == sizeof line.in)) return 1;
    }
}

static int listen_on(int port) {
    const int fd = socket(AF_INET, SOCK_STREAM, 0);
    const int one = 1;
    setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    struct sockaddr_in a = {0};
    a.sin_family = AF_INET;
    a.sin_port = htons((uint16_t)port);
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (bind(fd, (struct sockaddr*)&a, sizeof a) != 0 || listen(fd, 128) != 0) return -1;
    socklen_t len = sizeof a;
    getsockname(fd, (struct sockaddr*)&a, &len);
    printf("PORT %u\n", ntohs(a.sin_port));
    fflush(stdout);
    return fd;
}

int main(int argc, char** argv) {
    int port = 0;
    const char* tty = NULL;
    enum framing framing = kMbap;
    for (int i = 1; i + 1 < argc; i += 2) {
        if (strcmp(argv[i], "--port") == 0) port = atoi(argv[i + 1]);
        if (strcmp(argv[i], "--tty") == 0) tty = argv[i + 1];
        if (strcmp(argv[i], "--framing") == 0)
            framing = strcmp(argv[i + 1], "rtu") == 0     ? kRtu
                      : strcmp(argv[i + 1], "ascii") == 0 ? kAscii
                                                          : kMbap;
    }
    signal(SIGPIPE, SIG_IGN);
    signal(SIGUSR1, clear_registers);
    if (tty) return run_line(tty, framing == kMbap ? kRtu : framing);
    const int server = listen_on(port);
    if (server < 0) return 1;
    static struct client clients[kMaxClients];
    int count = 0;
    for (;;) {
        struct pollfd fds[kMaxClients + 1];
        fds[0] = (struct pollfd){server, POLLIN, 0};
        int waiting = 0;
        for (int i = 0; i < count; ++i) {
            fds[i + 1] = (struct pollfd){clients[i].fd, POLLIN, 0};
            waiting |= clients[i].size > 0;
        }
        if (poll(fds, (nfds_t)count + 1, waiting && framing != kMbap ? 50 : -1) < 0) continue;
        for (int i = count - 1; i >= 0; --i) {
            struct client* c = &clients[i];
            if (!fds[i + 1].revents) {
                if (framing != kMbap && c->size && now_ms() - c->last_byte_ms >= kTcpQuietMs)
                    c->size = 0;
                continue;
            }
            const ssize_t n = recv(c->fd, c->in + c->size, sizeof c->in - c->size, 0);
            if (n > 0) c->size += (size_t)n;
            c->last_byte_ms = now_ms();
            const int ok = framing == kMbap ? serve(c) : serve_serial(c, framing, 0);
            if (n <= 0 || !ok || c->size == sizeof c->in) {
                close(c->fd);
                clients[i] = clients[--count];
            }
        }
        if ((fds[0].revents & POLLIN) && count < kMaxClients) {
            const int fd = accept(server, NULL, NULL);
            if (fd >= 0) {
                const int one = 1;
                setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
                clients[count].fd = fd;
                clients[count].size = 0;
                ++count;
            }
        }
    }
}
