/*
 * soak.c -- N threads x M instances x K random increments through the C API, then a
 * serial replay. Every instance follows its own seeded random walk of macro strains
 * (steps of up to 2e-5 per component inside |eps| <= 1.2e-4, the pre-peak range of the
 * paper's RVE): each increment is a trial update that is committed (85 %) or reverted
 * (10 %), or a NaN strain that must be refused (5 %); every 25th increment saves the
 * committed state and loads it back (after a reset one time in four). Instance i runs on
 * thread i mod N; the threads meet at a barrier after each round (one increment of every
 * instance); every K/10 rounds thread 0 samples the RSS, the heap in use (glibc's
 * mallinfo2), the committed state bytes, the open file descriptors and the threads.
 *
 * Checks: every status is the expected one; the stresses, tangents and final state bytes
 * of the replayed instances (every R-th, on one thread, fresh instances) are bit-identical
 * to the threaded run; no file descriptor or thread growth between the sample at K/10
 * rounds and the one at K; with -f, the RSS at K rounds is within 1 % of the RSS at K/10
 * rounds (10^5 and 10^6 updates for M = 1000, K = 1000).
 *
 * Usage: soak [-t N] [-m M] [-k K] [-r R] [-s SEED] [-f] [SCENE.toml]
 * Defaults (the short version run by scripts/test-c): N = 2, M = 6, K = 30, R = 1,
 * seed 1, scenes/paper_rve_host.toml. studies/soak/run runs the long version.
 */
#define _POSIX_C_SOURCE 200809L
#include <dirent.h>
#ifdef __GLIBC__
#include <malloc.h>
#endif
#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "rve.h"

#define STEP 2e-5
#define BOX 1.2e-4
#define ROUND_TRIP_EVERY 25

typedef struct {
    uint64_t rng;
    double committed[3];
    uint64_t hash;
    long updates, commits, reverts, round_trips, failures, refusals;
} Walk;

static int n_threads = 2, n_instances = 6, n_rounds = 30, replay_every = 1, flat = 0;
static uint64_t seed = 1;
static const char *scene = "scenes/paper_rve_host.toml";
static RveHandle *handles;
static Walk *walks;
static uint64_t *final_state_hash;
static pthread_barrier_t barrier;
static int errors = 0;
static pthread_mutex_t error_lock = PTHREAD_MUTEX_INITIALIZER;

typedef struct {
    long rss_kib, fds, threads, round;
    double state_mib, heap_mib;
} Sample;
/* Samples after rounds K/10, 2K/10, ..., K. */
static Sample samples[10];
static int n_samples = 0;

static uint64_t splitmix(uint64_t *s) {
    uint64_t z = (*s += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

/* Uniform in [-1, 1). */
static double uniform(uint64_t *s) { return (double)(splitmix(s) >> 11) / 4503599627370496.0 - 1.0; }

static uint64_t fnv(uint64_t h, const void *data, size_t n) {
    const unsigned char *p = data;
    size_t i;
    for (i = 0; i < n; i++) h = (h ^ p[i]) * 0x100000001b3ULL;
    return h;
}

static void fail(const char *what, int instance, long step, uint32_t status) {
    char msg[512];
    rve_last_error(msg, sizeof msg);
    pthread_mutex_lock(&error_lock);
    if (errors++ < 10)
        fprintf(stderr, "instance %d step %ld: %s: status %u (%s) %s\n", instance, step, what,
                (unsigned)status, rve_status_message(status), msg);
    pthread_mutex_unlock(&error_lock);
}

/* Saves the committed state of h; returns its bytes (malloc'd) and size, or NULL. */
static uint8_t *save(RveHandle h, size_t *size) {
    uint8_t *buf;
    size_t written = 0;
    if (rve_state_size(h, size) != RVE_STATUS_OK) return NULL;
    buf = malloc(*size);
    if (buf && rve_state_save(h, buf, *size, &written) != RVE_STATUS_OK) {
        free(buf);
        return NULL;
    }
    return buf;
}

/* Increment `step` of instance k's walk w on handle h. */
static void increment(RveHandle h, Walk *w, int k, long step) {
    double u = 0.5 * (uniform(&w->rng) + 1.0), eps[3], stress[3], tangent[9];
    uint32_t s;
    int c;
    for (c = 0; c < 3; c++) {
        eps[c] = w->committed[c] + STEP * uniform(&w->rng);
        if (fabs(eps[c]) > BOX) eps[c] = w->committed[c] - (eps[c] - w->committed[c]);
    }
    if (u < 0.05) {
        eps[(int)(u * 60.0)] = NAN;
        s = rve_update(h, eps, stress, tangent, RVE_TANGENT_REQUEST_CONSISTENT);
        if (s != RVE_STATUS_NON_FINITE_STRAIN) fail("NaN strain not refused", k, step, s);
        w->refusals++;
    } else {
        s = rve_update(h, eps, stress, tangent, RVE_TANGENT_REQUEST_CONSISTENT);
        w->updates++;
        if (s == RVE_STATUS_SOLVER_FAILED) {
            w->failures++;
        } else if (s != RVE_STATUS_OK) {
            fail("update", k, step, s);
        } else {
            w->hash = fnv(w->hash, stress, sizeof stress);
            w->hash = fnv(w->hash, tangent, sizeof tangent);
            if (u < 0.15) {
                if ((s = rve_revert(h)) != RVE_STATUS_OK) fail("revert", k, step, s);
                w->reverts++;
            } else {
                if ((s = rve_commit(h)) != RVE_STATUS_OK) fail("commit", k, step, s);
                memcpy(w->committed, eps, sizeof eps);
                w->commits++;
            }
        }
    }
    if (step % ROUND_TRIP_EVERY == ROUND_TRIP_EVERY - 1) {
        size_t size = 0;
        uint8_t *bytes = save(h, &size);
        if (!bytes) {
            fail("save", k, step, 0);
            return;
        }
        if (splitmix(&w->rng) % 4 == 0 && (s = rve_reset(h)) != RVE_STATUS_OK) fail("reset", k, step, s);
        if ((s = rve_state_load(h, bytes, size)) != RVE_STATUS_OK) fail("load", k, step, s);
        free(bytes);
        w->round_trips++;
    }
}

static void walk_init(Walk *w, int k) {
    memset(w, 0, sizeof *w);
    w->rng = seed * 0x100000001ULL + (uint64_t)k;
    w->hash = 0xcbf29ce484222325ULL;
}

static long count_fds(void) {
    long n = 0;
    struct dirent *e;
    DIR *d = opendir("/proc/self/fd");
    if (!d) return -1;
    while ((e = readdir(d)) != NULL)
        if (e->d_name[0] != '.') n++;
    closedir(d);
    return n - 1; /* the directory stream itself */
}

static long status_field(const char *name) {
    char line[256];
    long v = -1;
    size_t n = strlen(name);
    FILE *f = fopen("/proc/self/status", "r");
    if (!f) return -1;
    while (fgets(line, sizeof line, f))
        if (strncmp(line, name, n) == 0) {
            v = strtol(line + n, NULL, 10);
            break;
        }
    fclose(f);
    return v;
}

static Sample sample(long round) {
    Sample s;
    int k;
    s.state_mib = 0.0;
    s.heap_mib = -1.0;
#if defined(__GLIBC__) && (__GLIBC__ > 2 || __GLIBC_MINOR__ >= 33)
    {
        /* Bytes allocated and not freed, over every malloc arena. */
        struct mallinfo2 mi = mallinfo2();
        s.heap_mib = (double)(mi.uordblks + mi.hblkhd) / 1048576.0;
    }
#endif
    for (k = 0; k < n_instances; k++) {
        size_t size = 0;
        if (rve_state_size(handles[k], &size) == RVE_STATUS_OK) s.state_mib += (double)size / 1048576.0;
    }
    s.fds = count_fds();
    s.threads = status_field("Threads:");
    s.rss_kib = status_field("VmRSS:");
    s.round = round;
    return s;
}

static void *worker(void *arg) {
    int t = *(int *)arg, k;
    long j, every = n_rounds >= 10 ? n_rounds / 10 : 1;
    for (j = 0; j < n_rounds; j++) {
        for (k = t; k < n_instances; k += n_threads) increment(handles[k], &walks[k], k, j);
        pthread_barrier_wait(&barrier);
        /* The same decision on every thread (from j alone), or a barrier waits forever. */
        if ((j + 1) % every == 0 && (j + 1) / every <= 10) {
            /* Every thread waits while thread 0 samples (it reads every instance). */
            if (t == 0) samples[n_samples++] = sample(j + 1);
            pthread_barrier_wait(&barrier);
        }
    }
    for (k = t; k < n_instances; k += n_threads) {
        size_t size = 0;
        uint8_t *bytes = save(handles[k], &size);
        if (!bytes) fail("final save", k, n_rounds, 0);
        final_state_hash[k] = bytes ? fnv(0xcbf29ce484222325ULL, bytes, size) : 0;
        free(bytes);
    }
    return NULL;
}

static double now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

int main(int argc, char **argv) {
    int i, k, replayed = 0, mismatches = 0;
    long j;
    pthread_t *th;
    int *ids;
    double t0, t1, t2;
    Walk total;
    Sample first, last;
    for (i = 1; i < argc; i++) {
        if (strcmp(argv[i], "-f") == 0) flat = 1;
        else if (argv[i][0] == '-' && i + 1 < argc) {
            long v = atol(argv[i + 1]);
            switch (argv[i][1]) {
                case 't': n_threads = (int)v; break;
                case 'm': n_instances = (int)v; break;
                case 'k': n_rounds = (int)v; break;
                case 'r': replay_every = (int)v; break;
                case 's': seed = (uint64_t)v; break;
                default: fprintf(stderr, "unknown option %s\n", argv[i]); return 2;
            }
            i++;
        } else scene = argv[i];
    }
    if (n_threads < 1 || n_instances < n_threads || n_rounds < 1 || replay_every < 1) {
        fprintf(stderr, "usage: soak [-t N] [-m M >= N] [-k K] [-r R] [-s SEED] [-f] [SCENE]\n");
        return 2;
    }
    handles = calloc((size_t)n_instances, sizeof *handles);
    walks = calloc((size_t)n_instances, sizeof *walks);
    final_state_hash = calloc((size_t)n_instances, sizeof *final_state_hash);
    th = calloc((size_t)n_threads, sizeof *th);
    ids = calloc((size_t)n_threads, sizeof *ids);
    if (rve_init_file(scene, &handles[0]) != RVE_STATUS_OK) {
        fail("init", 0, 0, RVE_STATUS_BAD_SCENE);
        return 1;
    }
    for (k = 0; k < n_instances; k++) {
        if (k > 0 && rve_clone_model(handles[0], &handles[k]) != RVE_STATUS_OK) fail("clone", k, 0, 0);
        walk_init(&walks[k], k);
    }

    t0 = now();
    pthread_barrier_init(&barrier, NULL, (unsigned)n_threads);
    for (i = 0; i < n_threads; i++) {
        ids[i] = i;
        pthread_create(&th[i], NULL, worker, &ids[i]);
    }
    for (i = 0; i < n_threads; i++) pthread_join(th[i], NULL);
    pthread_barrier_destroy(&barrier);
    t1 = now();
    for (k = 0; k < n_instances; k++) rve_free(handles[k]);

    /* Serial replay of every R-th instance on this thread, on fresh instances. */
    for (k = 0; k < n_instances; k += replay_every) {
        Walk w;
        RveHandle h = 0;
        size_t size = 0;
        uint8_t *bytes;
        uint64_t state_hash;
        if (rve_init_file(scene, &h) != RVE_STATUS_OK) fail("replay init", k, 0, 0);
        walk_init(&w, k);
        for (j = 0; j < n_rounds; j++) increment(h, &w, k, j);
        bytes = save(h, &size);
        state_hash = bytes ? fnv(0xcbf29ce484222325ULL, bytes, size) : 0;
        free(bytes);
        rve_free(h);
        replayed++;
        if (w.hash != walks[k].hash || state_hash != final_state_hash[k] || w.commits != walks[k].commits) {
            if (mismatches++ < 10) fprintf(stderr, "instance %d: serial replay differs from the threaded run\n", k);
        }
    }
    t2 = now();

    memset(&total, 0, sizeof total);
    for (k = 0; k < n_instances; k++) {
        total.updates += walks[k].updates;
        total.commits += walks[k].commits;
        total.reverts += walks[k].reverts;
        total.round_trips += walks[k].round_trips;
        total.failures += walks[k].failures;
        total.refusals += walks[k].refusals;
    }
    printf("soak: %d threads x %d instances x %d increments (%s, seed %llu)\n", n_threads, n_instances,
           n_rounds, scene, (unsigned long long)seed);
    printf("  updates %ld (commits %ld, reverts %ld, solver failures %ld), NaN refusals %ld, "
           "save/load round trips %ld\n",
           total.updates, total.commits, total.reverts, total.failures, total.refusals, total.round_trips);
    printf("  threaded: %.1f s, %.0f us per update per thread; serial replay of %d instances: %.1f s\n",
           t1 - t0, 1e6 * (t1 - t0) * n_threads / (double)(total.updates + total.refusals), replayed, t2 - t1);
    first = samples[0];
    last = samples[n_samples - 1];
    printf("  round   updates   RSS MiB   heap in use MiB   committed states MiB   fds   threads\n");
    for (i = 0; i < n_samples; i++)
        printf("  %5ld %9ld %9.1f %17.1f %22.1f %5ld %9ld\n", samples[i].round,
               samples[i].round * n_instances, samples[i].rss_kib / 1024.0, samples[i].heap_mib,
               samples[i].state_mib, samples[i].fds, samples[i].threads);
    printf("  RSS after %ld updates / after %ld: %.4f; heap in use: %.4f\n", last.round * n_instances,
           first.round * n_instances, (double)last.rss_kib / (double)first.rss_kib,
           last.heap_mib / first.heap_mib);
    if (last.fds != first.fds || last.threads != first.threads) {
        fprintf(stderr, "file descriptors or threads grew\n");
        errors++;
    }
    if (flat && (double)last.rss_kib > 1.01 * (double)first.rss_kib) {
        fprintf(stderr, "RSS grew by more than 1 %%\n");
        errors++;
    }
    printf("  serial replay: %d of %d instances bit-identical to the threaded run\n", replayed - mismatches,
           replayed);
    free(handles);
    free(walks);
    free(final_state_hash);
    free(th);
    free(ids);
    if (errors || mismatches) {
        fprintf(stderr, "soak: FAILED (%d errors)\n", errors);
        return 1;
    }
    printf("soak: passed\n");
    return 0;
}
