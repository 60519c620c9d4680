/* A small Modbus TCP device on libmodbus, for grey-box runs against libmodbus itself
 * (bench/run_libmodbus_coverage.sh builds libmodbus from source with
 * -fsanitize-coverage=trace-pc-guard,trace-cmp,pc-table, then this device against it and
 * mbstorm's runtime). Everything it answers, libmodbus answers: modbus_receive and
 * modbus_reply over one mapping, as libmodbus's own unit-test server does, at that server's
 * addresses (none at 0), a few dozen entries per table:
 *   coils 0x130-0x154 (37), discrete inputs 0x1C4-0x1D9 (22),
 *   holding registers 0x160-0x17F (32), input registers 0x108-0x10F (8).
 * Many clients at once (a poll() loop, one modbus_t whose socket is set to the ready client),
 * since mbstorm probes on connections of its own beside the case's.
 *
 * Usage: libmodbus_coverage_device [--port P] [--response-timeout-ms MS]
 * prints "PORT <n>" once listening; runs until killed. After an exception 01 or 03 libmodbus
 * sleeps its response timeout (500 ms unless given), the whole server with it, then flushes:
 * a harness may shorten it so that a fuzzer's time is not spent waiting. */
#include <arpa/inet.h>
#include <errno.h>
#include <modbus.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

enum { kMaxClients = 1024 };

static modbus_mapping_t* new_mapping(void) {
    modbus_mapping_t* map =
        modbus_mapping_new_start_address(0x130, 37, 0x1C4, 22, 0x160, 32, 0x108, 8);
    if (!map) return NULL;
    /* Values that differ from their neighbours, so a wrong address reads a wrong value. */
    for (int i = 0; i < 32; ++i) map->tab_registers[i] = (uint16_t)(0x160 + i);
    for (int i = 0; i < 8; ++i) map->tab_input_registers[i] = (uint16_t)(0x1000 + i);
    for (int i = 0; i < 22; ++i) map->tab_input_bits[i] = (uint8_t)(i % 3 == 0);
    return map;
}

static int port_of(int fd) {
    struct sockaddr_in a;
    socklen_t len = sizeof a;
    getsockname(fd, (struct sockaddr*)&a, &len);
    return ntohs(a.sin_port);
}

static void accept_client(int server, struct pollfd* fds, int* count) {
    int fd = accept(server, NULL, NULL);
    if (fd < 0) return;
    if (*count >= kMaxClients) { /* full: refused, as a device out of sockets would */
        close(fd);
        return;
    }
    int one = 1;
    setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    fds[*count].fd = fd;
    fds[*count].events = POLLIN;
    ++*count;
}

/* One request from a ready client, answered by libmodbus. 0: the client is gone. */
static int serve_client(modbus_t* ctx, int fd, modbus_mapping_t* map) {
    uint8_t query[MODBUS_TCP_MAX_ADU_LENGTH];
    modbus_set_socket(ctx, fd);
    int rc = modbus_receive(ctx, query);
    if (rc > 0) modbus_reply(ctx, query, rc, map);
    return rc != -1;
}

static void serve(modbus_t* ctx, int server, modbus_mapping_t* map) {
    static struct pollfd fds[kMaxClients + 1];
    int count = 1;
    fds[0].fd = server;
    fds[0].events = POLLIN;
    for (;;) {
        if (poll(fds, (nfds_t)count, -1) < 0 && errno != EINTR) return;
        for (int i = count - 1; i >= 1; --i) {
            if (!(fds[i].revents & (POLLIN | POLLHUP | POLLERR))) continue;
            if (serve_client(ctx, fds[i].fd, map)) continue;
            close(fds[i].fd);
            fds[i] = fds[--count];
        }
        if (fds[0].revents & POLLIN) accept_client(server, fds, &count);
    }
}

int main(int argc, char** argv) {
    int port = 0, timeout_ms = -1;
    for (int i = 1; i + 1 < argc; i += 2) {
        if (strcmp(argv[i], "--port") == 0) port = atoi(argv[i + 1]);
        if (strcmp(argv[i], "--response-timeout-ms") == 0) timeout_ms = atoi(argv[i + 1]);
    }
    signal(SIGPIPE, SIG_IGN);
    modbus_t* ctx = modbus_new_tcp("127.0.0.1", port);
    modbus_mapping_t* map = new_mapping();
    if (!ctx || !map) {
        fprintf(stderr, "libmodbus_coverage_device: setup failed\n");
        return 1;
    }
    if (timeout_ms >= 0)
        modbus_set_response_timeout(ctx, (uint32_t)(timeout_ms / 1000),
                                    (uint32_t)(timeout_ms % 1000) * 1000);
    int server = modbus_tcp_listen(ctx, 1024);
    if (server < 0) {
        fprintf(stderr, "libmodbus_coverage_device: listen: %s\n", modbus_strerror(errno));
        return 1;
    }
    printf("PORT %d\n", port_of(server));
    fflush(stdout);
    serve(ctx, server, map);
    return 1;
}
