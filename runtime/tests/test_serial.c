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

/* The build of the tests links with -Wl,--wrap=clock_gettime: a kernel without a
 * monotonic clock (Linux 2.4, the TS-5500's) is one flag away. */
static int monotonic_clock_missing;
int __real_clock_gettime(clockid_t clock, struct timespec *ts);
int __wrap_clock_gettime(clockid_t clock, struct timespec *ts);
int __wrap_clock_gettime(clockid_t clock, struct timespec *ts)
{
    if (monotonic_clock_missing && clock == CLOCK_MONOTONIC) {
        errno = EINVAL;
        return -1;
    }
    return __real_clock_gettime(clock, ts);
}

void test_now_should_count_clock_ticks_on_a_kernel_without_a_monotonic_clock(void)
{
    monotonic_clock_missing = 1;
    double start = gp_now_s();
    struct timespec pause = {0, 300 * 1000 * 1000};
    nanosleep(&pause, NULL);
    double elapsed = gp_now_s() - start;
    monotonic_clock_missing = 0;
    CHECK(start > 0);
    CHECK(elapsed >= 0.25 && elapsed < 10.0);
}
