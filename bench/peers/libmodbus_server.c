/* Comparison peer: a libmodbus TCP server using libmodbus's documented select() pattern for
 * many clients (one modbus_t, modbus_set_socket per ready descriptor, receive + reply).
 *
 *   libmodbus_server [--port N] [--seconds S] [--sparse 1]
 * prints "PORT <n>" once listening. --sparse 1 gives it a map like libmodbus's own unit-test
 * server's (a few dozen entries per table, none at address 0) instead of 1000 from 0. */
#include <arpa/inet.h>
#include <errno.h>
#include <modbus.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/select.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

static volatile sig_atomic_t g_stop = 0;
static void on_signal(int sig) {
    (void)sig;
    g_stop = 1;
}

int main(int argc, char** argv) {
    int port = 0, sparse = 0;
    double seconds = 0;
    for (int i = 1; i + 1 < argc; i += 2) {
        if (strcmp(argv[i], "--port") == 0) port = atoi(argv[i + 1]);
        if (strcmp(argv[i], "--seconds") == 0) seconds = atof(argv[i + 1]);
        if (strcmp(argv[i], "--sparse") == 0) sparse = atoi(argv[i + 1]);
    }
    signal(SIGINT, on_signal);
    signal(SIGTERM, on_signal);
    signal(SIGPIPE, SIG_IGN);

    modbus_t* ctx = modbus_new_tcp("127.0.0.1", port);
    /* Sparse: coils 0x130 (37), discrete inputs 0x1C4 (22), holding registers 0x160 (32),
     * input registers 0x108 (1), the start addresses and sizes of libmodbus's unit tests. */
    modbus_mapping_t* map =
        sparse ? modbus_mapping_new_start_address(0x130, 0x25, 0x1C4, 0x16, 0x160, 0x20, 0x108, 1)
               : modbus_mapping_new(1000, 1000, 1000, 1000);
    if (!ctx || !map) {
        fprintf(stderr, "libmodbus_server: setup failed\n");
        return 1;
    }
    int server = modbus_tcp_listen(ctx, 1024);
    if (server < 0) {
        fprintf(stderr, "libmodbus_server: listen: %s\n", modbus_strerror(errno));
        return 1;
    }
    struct sockaddr_in addr;
    socklen_t len = sizeof addr;
    getsockname(server, (struct sockaddr*)&addr, &len);
    printf("PORT %u\n", ntohs(addr.sin_port));
    fflush(stdout);

    fd_set refset;
    FD_ZERO(&refset);
    FD_SET(server, &refset);
    int fdmax = server;
    uint8_t query[MODBUS_TCP_MAX_ADU_LENGTH];
    time_t end = seconds > 0 ? time(NULL) + (time_t)seconds + 1 : 0;

    while (!g_stop && (end == 0 || time(NULL) < end)) {
        fd_set rdset = refset;
        struct timeval tv = {0, 200000};
        int ready = select(fdmax + 1, &rdset, NULL, NULL, &tv);
        if (ready < 0) {
            if (errno == EINTR) continue;
            break;
        }
        for (int fd = 0; fd <= fdmax && ready > 0; ++fd) {
            if (!FD_ISSET(fd, &rdset)) continue;
            --ready;
            if (fd == server) {
                struct sockaddr_in client;
                socklen_t clen = sizeof client;
                int nfd = accept(server, (struct sockaddr*)&client, &clen);
                if (nfd < 0) continue;
                if (nfd >= FD_SETSIZE) { /* select() cannot watch it */
                    close(nfd);
                    continue;
                }
                /* Every server in the comparison answers with Nagle off, as libmodbus's
                 * own client does, so that delayed ACKs do not dominate pipelined runs. */
                int one = 1;
                setsockopt(nfd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
                FD_SET(nfd, &refset);
                if (nfd > fdmax) fdmax = nfd;
            } else {
                modbus_set_socket(ctx, fd);
                int rc = modbus_receive(ctx, query);
                if (rc > 0) {
                    modbus_reply(ctx, query, rc, map);
                } else if (rc == -1) {
                    close(fd);
                    FD_CLR(fd, &refset);
                    if (fd == fdmax) fdmax--;
                }
            }
        }
    }
    close(server);
    modbus_mapping_free(map);
    modbus_free(ctx);
    return 0;
}
