/* mbstorm's coverage runtime: build it into a Modbus server to fuzz it with `mbstorm fuzz
 * --coverage`. It needs plain clang, nothing else:
 *
 *   clang -g -fsanitize-coverage=trace-pc-guard,trace-cmp,pc-table -c server.c
 *   clang -c /usr/share/mbstorm/coverage/mbstorm_coverage.c      (no coverage flags here)
 *   clang server.o mbstorm_coverage.o -o server
 *
 * (pc-table is optional: only `mbstorm fuzz --coverage-report` needs it.)
 *
 * mbstorm starts the server (--target-cmd) with the id of a System V shared-memory segment in
 * __AFL_SHM_ID and its map size in AFL_MAP_SIZE, as AFL++ does, so a server built with AFL++'s
 * compilers works the same way. Each instrumented edge counts its hits in one byte of the
 * map; mbstorm clears the map before a case and reads it after.
 *
 * Past the map, this runtime also logs the operands of the comparisons the server makes
 * (1, 2, 4 and 8 bytes, and switch cases), once per comparison site per case: mbstorm turns
 * the constants a server compares its input against into values and addresses to try.
 *
 * With pc-table, each module's table of (PC, flags) pairs, one per guard in the guards' order,
 * tells which guard is a function's entry: the runtime lists those functions, as offsets in
 * their module (what addr2line takes) with their guard, in the file named by
 * MBSTORM_COVERAGE_PCS (mbstorm sets it for --coverage-report), appending
 *   module /path/of/the/module
 *   0x<offset> <guard>        one line per function
 * for each module (a restarted server appends the same lines again). mbstorm then names the
 * functions whose entry guard no case hit.
 *
 * Without __AFL_SHM_ID (the server run on its own) the counts go to a private map. */
#define _GNU_SOURCE /* dl_iterate_phdr */
#include <link.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/shm.h>
#include <unistd.h>

/* The layout past the map; mbstorm reads it (src/netfuzz/coverage_map.hpp). */
#define MBSTORM_CMP_MAGIC 0x504D434DU /* "MCMP" */
#define MBSTORM_CMP_SITES 4096        /* bits: comparison sites already logged this case */
#define MBSTORM_CMP_ENTRIES 1024

struct mbstorm_cmp_entry {
    uint32_t size; /* operand size in bytes; 0x80 set: the first operand is a constant */
    uint32_t reserved;
    uint64_t a, b;
};

struct mbstorm_cmp_log {
    uint32_t magic;
    uint32_t count; /* entries used this case; mbstorm sets it to 0 before each case */
    uint8_t sites[MBSTORM_CMP_SITES / 8];
    struct mbstorm_cmp_entry entries[MBSTORM_CMP_ENTRIES];
};

static uint8_t private_map[1 << 16];
static uint8_t* map = private_map;
static uint32_t map_size = sizeof private_map;
static struct mbstorm_cmp_log* cmp_log;
static uint32_t next_guard = 1;
/* The guards numbered last: clang calls __sanitizer_cov_pcs_init for the same module next. */
static const uint32_t* last_guards;
static const uint32_t* last_guards_end;

static void attach(void) {
    static int attached;
    if (attached) return;
    attached = 1;
    const char* id = getenv("__AFL_SHM_ID");
    const char* size = getenv("AFL_MAP_SIZE");
    if (!id) return;
    void* shared = shmat(atoi(id), NULL, 0);
    if (shared == (void*)-1) return;
    map = shared;
    map_size = size ? (uint32_t)strtoul(size, NULL, 10) : 1U << 16;
    if (map_size < 64) map_size = 64;
    cmp_log = (struct mbstorm_cmp_log*)(map + map_size);
    cmp_log->magic = MBSTORM_CMP_MAGIC;
}

/* Numbers the module's edges 1..n (0 stays unused, as in AFL: an empty byte means no hit). */
void __sanitizer_cov_trace_pc_guard_init(uint32_t* start, uint32_t* stop) {
    attach();
    last_guards = start;
    last_guards_end = stop;
    if (start == stop || *start) return;
    for (uint32_t* g = start; g < stop; ++g) {
        *g = next_guard % map_size;
        if (*g == 0) *g = 1;
        ++next_guard;
    }
}

void __sanitizer_cov_trace_pc_guard(uint32_t* guard) {
    uint8_t* cell = &map[*guard];
    /* Never wraps back to 0, as AFL++'s NeverZero: 255 hits are not "no hit". */
    *cell = (uint8_t)(*cell + 1 + (*cell == 255));
}

static void log_cmp(uintptr_t site, uint32_t size, uint64_t a, uint64_t b) {
    if (!cmp_log || a == b) return; /* an equal comparison was passed already */
    const uint32_t bit = (uint32_t)((site >> 2) ^ (site >> 14)) % MBSTORM_CMP_SITES;
    if (cmp_log->sites[bit / 8] & (1U << (bit % 8))) return;
    cmp_log->sites[bit / 8] |= (uint8_t)(1U << (bit % 8));
    const uint32_t n = cmp_log->count;
    if (n >= MBSTORM_CMP_ENTRIES) return;
    cmp_log->entries[n].size = size;
    cmp_log->entries[n].a = a;
    cmp_log->entries[n].b = b;
    cmp_log->count = n + 1;
}

#define SITE ((uintptr_t)__builtin_return_address(0))
void __sanitizer_cov_trace_cmp1(uint8_t a, uint8_t b) { log_cmp(SITE, 1, a, b); }
void __sanitizer_cov_trace_cmp2(uint16_t a, uint16_t b) { log_cmp(SITE, 2, a, b); }
void __sanitizer_cov_trace_cmp4(uint32_t a, uint32_t b) { log_cmp(SITE, 4, a, b); }
void __sanitizer_cov_trace_cmp8(uint64_t a, uint64_t b) { log_cmp(SITE, 8, a, b); }
void __sanitizer_cov_trace_const_cmp1(uint8_t a, uint8_t b) { log_cmp(SITE, 0x81, a, b); }
void __sanitizer_cov_trace_const_cmp2(uint16_t a, uint16_t b) { log_cmp(SITE, 0x82, a, b); }
void __sanitizer_cov_trace_const_cmp4(uint32_t a, uint32_t b) { log_cmp(SITE, 0x84, a, b); }
void __sanitizer_cov_trace_const_cmp8(uint64_t a, uint64_t b) { log_cmp(SITE, 0x88, a, b); }

/* cases[0]: how many, cases[1]: the operand's size in bits, then the case values. */
void __sanitizer_cov_trace_switch(uint64_t value, uint64_t* cases) {
    const uint32_t bytes = (uint32_t)(cases[1] / 8);
    for (uint64_t i = 0; i < cases[0]; ++i)
        log_cmp(SITE + (uintptr_t)i * 4, 0x80 | bytes, cases[2 + i], value);
}

/* The division and GEP hooks trace-cmp does not enable are not needed. */

struct module_search {
    uintptr_t pc;
    uintptr_t base;  /* what the module's addresses are relative to */
    char path[4096]; /* "" until found */
};

static int find_module(struct dl_phdr_info* info, size_t size, void* data) {
    (void)size;
    struct module_search* m = data;
    for (int i = 0; i < info->dlpi_phnum; ++i) {
        const ElfW(Phdr)* ph = &info->dlpi_phdr[i];
        const uintptr_t start = info->dlpi_addr + ph->p_vaddr;
        if (ph->p_type != PT_LOAD || m->pc < start || m->pc >= start + ph->p_memsz) continue;
        m->base = info->dlpi_addr;
        if (info->dlpi_name && info->dlpi_name[0]) {
            snprintf(m->path, sizeof m->path, "%s", info->dlpi_name);
        } else { /* the executable itself: its name is not in the list */
            const ssize_t n = readlink("/proc/self/exe", m->path, sizeof m->path - 1);
            m->path[n > 0 ? n : 0] = 0;
        }
        return 1;
    }
    return 0;
}

/* -fsanitize-coverage=pc-table: (PC, flags) pairs, flags bit 1 for a function's entry block.
 * Runs once per module at start-up, never in the hit path. */
void __sanitizer_cov_pcs_init(const uintptr_t* begin, const uintptr_t* end) {
    const char* path = getenv("MBSTORM_COVERAGE_PCS");
    if (!path || begin == end || !last_guards) return;
    const size_t count = (size_t)(end - begin) / 2;
    /* Not the guards numbered last (built without trace-pc-guard): no guard to name. */
    if (count != (size_t)(last_guards_end - last_guards)) return;
    struct module_search m = {.pc = begin[0]};
    dl_iterate_phdr(find_module, &m);
    if (!m.path[0]) return;
    FILE* out = fopen(path, "a");
    if (!out) return;
    fprintf(out, "module %s\n", m.path);
    for (size_t i = 0; i < count; ++i)
        if (begin[2 * i + 1] & 1)
            fprintf(out, "0x%llx %u\n", (unsigned long long)(begin[2 * i] - m.base),
                    (unsigned)last_guards[i]);
    fclose(out);
}
