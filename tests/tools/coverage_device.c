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
 * Usage: coverage_device [--port P]   prints "PORT <n>" once listening; runs until killed. */
#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

enum { kRegisters = 1000, kMaxClients = 1024, kBuffer = 4096 };
enum { kRead = 0x03, kWriteOne = 0x06, kWriteMany = 0x10, kMaskWrite = 0x16 };
enum { kIllegalFunction = 1, kIllegalAddress = 2, kIllegalValue = 3 };

static uint16_t registers[kRegisters];
static uint16_t* volatile null_register; /* volatile: the compiler may not assume it away */

struct client {
    int fd;
    uint8_t in[kBuffer];
    size_t size;
};

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
    for (int i = 1; i + 1 < argc; i += 2)
        if (strcmp(argv[i], "--port") == 0) port = atoi(argv[i + 1]);
    signal(SIGPIPE, SIG_IGN);
    signal(SIGUSR1, clear_registers);
    const int server = listen_on(port);
    if (server < 0) return 1;
    static struct client clients[kMaxClients];
    int count = 0;
    for (;;) {
        struct pollfd fds[kMaxClients + 1];
        fds[0] = (struct pollfd){server, POLLIN, 0};
        for (int i = 0; i < count; ++i) fds[i + 1] = (struct pollfd){clients[i].fd, POLLIN, 0};
        if (poll(fds, (nfds_t)count + 1, -1) < 0) continue;
        for (int i = count - 1; i >= 0; --i) {
            if (!fds[i + 1].revents) continue;
            struct client* c = &clients[i];
            const ssize_t n = recv(c->fd, c->in + c->size, sizeof c->in - c->size, 0);
            if (n > 0) c->size += (size_t)n;
            if (n <= 0 || !serve(c) || c->size == sizeof c->in) {
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
