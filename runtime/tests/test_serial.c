/* The pseudo-terminal of `--device pty`: raw bytes both ways between the master and
 * the path it names, and the linger before closing that ends when the peer hangs up
 * and otherwise at its bound. */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <fcntl.h>
#include <time.h>
#include <unistd.h>

#include "gp_serial.h"
#include "gp_test.h"

static long read_all(int fd, uint8_t *buf, size_t want)
{
    size_t got = 0;
    for (int attempt = 0; got < want && attempt < 100; attempt++) {
        long n = gp_serial_read(fd, buf + got, want - got, 100);
        if (n < 0) {
            return -1;
        }
        got += (size_t)n;
    }
    return (long)got;
}

void test_pty_should_carry_raw_bytes_to_the_path_it_names(void)
{
    char path[128];
    int master = gp_serial_open_pty(path, sizeof path);
    CHECK(master >= 0);
    CHECK(strncmp(path, "/dev/pts/", 9) == 0);
    int peer = gp_serial_open(path);
    CHECK(peer >= 0);
    /* NUL, CR, LF, XON, XOFF, ^C and 0xFF must pass untouched: the line is raw */
    const uint8_t sent[] = {0x00, '\r', '\n', 0x11, 0x13, 0x03, 0xFF, 'x'};
    uint8_t got[sizeof sent];
    CHECK_INT(gp_serial_write(master, sent, sizeof sent), 0);
    CHECK_INT(read_all(peer, got, sizeof got), sizeof sent);
    CHECK(memcmp(got, sent, sizeof sent) == 0);
    CHECK_INT(gp_serial_write(peer, sent, sizeof sent), 0);
    CHECK_INT(read_all(master, got, sizeof got), sizeof sent);
    CHECK(memcmp(got, sent, sizeof sent) == 0);
    close(peer);
    close(master);
}

void test_pty_should_refuse_a_path_buffer_too_small(void)
{
    char path[4];
    CHECK_INT(gp_serial_open_pty(path, sizeof path), -1);
}

void test_linger_should_end_when_the_peer_hangs_up_and_else_at_its_bound(void)
{
    char path[128];
    int master = gp_serial_open_pty(path, sizeof path);
    int peer = gp_serial_open(path);
    CHECK(master >= 0 && peer >= 0);
    double start = gp_now_s();
    gp_serial_linger(master, 0.3, NULL, NULL);  /* peer still open: waits out its bound */
    CHECK(gp_now_s() - start >= 0.3);
    close(peer);
    start = gp_now_s();
    gp_serial_linger(master, 60.0, NULL, NULL);  /* peer gone: returns at once, not after 60 s */
    CHECK(gp_now_s() - start < 30.0);
    close(master);
}

/* The tests' build wraps the clock and the nap (-Wl,--wrap=...). musl on a 32-bit board
 * (the TS-5500's) links the runtime's calls to them by their 64-bit-time names. */
#if defined(_REDIR_TIME64) && _REDIR_TIME64
#define WRAP(name, time64_name) __wrap_##time64_name
#define REAL(name, time64_name) __real_##time64_name
#else
#define WRAP(name, time64_name) __wrap_##name
#define REAL(name, time64_name) __real_##name
#endif

/* The nap: the longest one asked for while `naps_watched` is set. */
static int naps_watched;
static long longest_nap_ms;
int REAL(nanosleep, __nanosleep_time64)(const struct timespec *request,
                                        struct timespec *remaining);
int WRAP(nanosleep, __nanosleep_time64)(const struct timespec *request,
                                        struct timespec *remaining);
int WRAP(nanosleep, __nanosleep_time64)(const struct timespec *request,
                                        struct timespec *remaining)
{
    long ms = (long)request->tv_sec * 1000L + request->tv_nsec / 1000000L;
    if (naps_watched && ms > longest_nap_ms) {
        longest_nap_ms = ms;
    }
    return REAL(nanosleep, __nanosleep_time64)(request, remaining);
}

/* The simulator hangs up, then stops the runtime (SIGTERM). A stop signal that landed
 * between the read's poll and its nap once waited out the read's whole timeout (what
 * was left of the watchdog) before the loop saw it, and the simulator killed the
 * runtime after 5 s: on a hung-up line the read naps at most 50 ms, whatever its
 * timeout. */
void test_read_should_nap_briefly_on_a_line_whose_peer_hung_up(void)
{
    char path[128];
    int master = gp_serial_open_pty(path, sizeof path);
    int peer = gp_serial_open(path);
    CHECK(master >= 0 && peer >= 0);
    close(peer);
    uint8_t byte;
    naps_watched = 1;
    longest_nap_ms = 0;
    CHECK_INT(gp_serial_read(master, &byte, 1, 5000), 0);
    naps_watched = 0;
    CHECK(longest_nap_ms > 0);  /* it did wait, as if the line were silent */
    CHECK(longest_nap_ms <= 50);
    close(master);
}

/* The clock: a kernel without a monotonic clock (Linux 2.4, the TS-5500's) is one flag
 * away. */
static int monotonic_clock_missing, monotonic_clock_refused;
int REAL(clock_gettime, __clock_gettime64)(clockid_t clock, struct timespec *ts);
int WRAP(clock_gettime, __clock_gettime64)(clockid_t clock, struct timespec *ts);
int WRAP(clock_gettime, __clock_gettime64)(clockid_t clock, struct timespec *ts)
{
    if (monotonic_clock_missing && clock == CLOCK_MONOTONIC) {
        monotonic_clock_refused++;
        errno = EINVAL;
        return -1;
    }
    return REAL(clock_gettime, __clock_gettime64)(clock, ts);
}

void test_now_should_count_clock_ticks_on_a_kernel_without_a_monotonic_clock(void)
{
    monotonic_clock_missing = 1;
    double start = gp_now_s();
    struct timespec pause = {0, 300 * 1000 * 1000};
    nanosleep(&pause, NULL);
    double elapsed = gp_now_s() - start;
    monotonic_clock_missing = 0;
    CHECK(monotonic_clock_refused >= 2);  /* both readings asked the clock that is not there */
    CHECK(start > 0);
    CHECK(elapsed >= 0.25 && elapsed < 10.0);
}
