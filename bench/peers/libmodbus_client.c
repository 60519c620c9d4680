/* A load client written the way libmodbus users write one: N threads, each with one blocking
 * connection, reading 10 holding registers in a loop (no pipelining; libmodbus has none).
 *
 *   libmodbus_client HOST PORT THREADS SECONDS
 * Prints "transactions N seconds S tx_per_s R errors E".
 */
#include <errno.h>
#include <modbus.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

struct worker {
    const char* host;
    int port;
    double seconds;
    unsigned long long transactions;
    unsigned long long errors;
};

static double now_seconds(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec / 1e9;
}

static void* run_worker(void* arg) {
    struct worker* w = arg;
    modbus_t* ctx = modbus_new_tcp(w->host, w->port);
    if (!ctx || modbus_connect(ctx) == -1) {
        fprintf(stderr, "libmodbus_client: connect: %s\n", modbus_strerror(errno));
        w->errors++;
        if (ctx) modbus_free(ctx);
        return NULL;
    }
    modbus_set_response_timeout(ctx, 2, 0);
    uint16_t regs[10];
    const double end = now_seconds() + w->seconds;
    while (now_seconds() < end) {
        /* Check the clock only every 64 requests so it costs nothing measurable. */
        for (int i = 0; i < 64; ++i) {
            if (modbus_read_registers(ctx, 0, 10, regs) == 10)
                w->transactions++;
            else
                w->errors++;
        }
    }
    modbus_close(ctx);
    modbus_free(ctx);
    return NULL;
}

int main(int argc, char** argv) {
    if (argc != 5) {
        fprintf(stderr, "usage: libmodbus_client HOST PORT THREADS SECONDS\n");
        return 2;
    }
    int threads = atoi(argv[3]);
    if (threads < 1 || threads > 4096) return 2;
    struct worker* workers = calloc((size_t)threads, sizeof *workers);
    pthread_t* ids = calloc((size_t)threads, sizeof *ids);
    if (!workers || !ids) return 1;
    double start = now_seconds();
    for (int i = 0; i < threads; ++i) {
        workers[i].host = argv[1];
        workers[i].port = atoi(argv[2]);
        workers[i].seconds = atof(argv[4]);
        pthread_create(&ids[i], NULL, run_worker, &workers[i]);
    }
    unsigned long long total = 0, errors = 0;
    for (int i = 0; i < threads; ++i) {
        pthread_join(ids[i], NULL);
        total += workers[i].transactions;
        errors += workers[i].errors;
    }
    double elapsed = now_seconds() - start;
    printf("transactions %llu seconds %.3f tx_per_s %.0f errors %llu\n", total, elapsed,
           (double)total / elapsed, errors);
    free(workers);
    free(ids);
    return 0;
}
