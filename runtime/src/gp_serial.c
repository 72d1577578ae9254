/* POSIX serial I/O. A hung-up peer (the other end of a pty closed, or not yet opened)
 * reads as silence, so the watchdog, not an error path, decides when to give control
 * back. The line is non-blocking both ways: a peer that stops reading costs a frame,
 * never the runtime's loop (its watchdog and its stop signals). */
#define _XOPEN_SOURCE 700 /* posix_openpt, grantpt, unlockpt, ptsname */
#include "gp_serial.h"

#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <stdlib.h>
#include <string.h>
#include <sys/ioctl.h>
#include <sys/times.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

#include "gp_contract.h"

#define WRITE_WAIT_MS 1000  /* [ms] the longest a frame waits for room on the line */
#define DRAIN_NAP_MS 10     /* [ms] between looks at the output queue */
#define HUNG_UP_NAP_MS 50  /* [ms] the longest wait on a line nobody holds */

/* termios names its speeds: the contract's line speed is the one set below. */
_Static_assert(GP_BAUD == 115200, "make_raw sets B115200: set the contract's GP_BAUD");

/* Raw 115200 8N1, no flow control; reads return what is there (VMIN = VTIME = 0). */
static int make_raw(int fd)
{
    struct termios tio;
    if (tcgetattr(fd, &tio) < 0) {
        return -1;
    }
    tio.c_iflag &= ~(tcflag_t)(IGNBRK | BRKINT | PARMRK | ISTRIP | INLCR | IGNCR | ICRNL | IXON
                               | IXOFF | IXANY);
    tio.c_oflag &= ~(tcflag_t)OPOST;
    tio.c_lflag &= ~(tcflag_t)(ECHO | ECHONL | ICANON | ISIG | IEXTEN);
    tio.c_cflag &= ~(tcflag_t)(CSIZE | PARENB | CSTOPB);
    tio.c_cflag |= CS8 | CLOCAL | CREAD;
    tio.c_cc[VMIN] = 0;
    tio.c_cc[VTIME] = 0;
    if (cfsetispeed(&tio, B115200) < 0 || cfsetospeed(&tio, B115200) < 0
        || tcsetattr(fd, TCSANOW, &tio) < 0) {
        return -1;
    }
    return 0;
}

static int close_keeping_errno(int fd)
{
    int saved = errno;
    close(fd);
    errno = saved;
    return -1;
}

int gp_serial_open(const char *path)
{
    int fd = open(path, O_RDWR | O_NOCTTY | O_NONBLOCK);
    if (fd < 0) {
        return -1;
    }
    return make_raw(fd) < 0 ? close_keeping_errno(fd) : fd;
}

int gp_serial_open_pty(char *peer_path, size_t cap)
{
    int fd = posix_openpt(O_RDWR | O_NOCTTY);
    if (fd < 0) {
        return -1;
    }
    const char *name = NULL;
    if (grantpt(fd) < 0 || unlockpt(fd) < 0 || (name = ptsname(fd)) == NULL
        || make_raw(fd) < 0 || fcntl(fd, F_SETFL, fcntl(fd, F_GETFL) | O_NONBLOCK) < 0) {
        return close_keeping_errno(fd);
    }
    size_t len = strlen(name);
    if (len >= cap) {
        errno = ENAMETOOLONG;
        return close_keeping_errno(fd);
    }
    memcpy(peer_path, name, len + 1);
    return fd;
}

void gp_serial_linger(int fd, double max_s, gp_serial_bytes_fn on_bytes, void *ctx)
{
    uint8_t got[64];
    for (double until = gp_now_s() + max_s; gp_now_s() < until;) {
        struct pollfd pfd = {.fd = fd, .events = POLLIN};
        int ready = poll(&pfd, 1, 50);
        if (ready > 0 && (pfd.revents & POLLHUP)) {
            return;
        }
        ssize_t n = ready > 0 ? read(fd, got, sizeof got) : 0;
        if (n < 0 && errno != EINTR && errno != EAGAIN) {
            return;
        }
        if (n > 0 && on_bytes) {
            on_bytes(ctx, got, (size_t)n);
        }
    }
}

int gp_serial_write(int fd, const uint8_t *data, size_t len)
{
    double give_up = 0;  /* set when the line is first found full: most writes never wait */
    while (len > 0) {
        ssize_t n = write(fd, data, len);
        if (n > 0) {
            data += n;
            len -= (size_t)n;
            continue;
        }
        if (n < 0 && errno != EAGAIN && errno != EINTR) {
            return -1;
        }
        /* the line is full: wait for room, but a signal or the bound ends the wait */
        double now = gp_now_s();
        if (give_up == 0) {
            give_up = now + WRITE_WAIT_MS / 1000.0;
        }
        int wait_ms = (int)((give_up - now) * 1000.0);
        struct pollfd pfd = {.fd = fd, .events = POLLOUT};
        if (wait_ms <= 0 || poll(&pfd, 1, wait_ms) <= 0) {
            return -1;
        }
    }
    return 0;
}

void gp_serial_drain(int fd, double max_s)
{
    int queued = 0;
    for (double until = gp_now_s() + max_s; gp_now_s() < until;) {
        if (ioctl(fd, TIOCOUTQ, &queued) < 0 || queued <= 0) {
            return;
        }
        struct timespec nap = {0, DRAIN_NAP_MS * 1000000L};
        if (nanosleep(&nap, NULL) < 0) {
            return;  /* a signal: the caller is on its way out */
        }
    }
}

static void sleep_ms(int ms)
{
    struct timespec ts = {ms / 1000, (long)(ms % 1000) * 1000000L};
    nanosleep(&ts, NULL);
}

long gp_serial_read(int fd, uint8_t *buf, size_t cap, int timeout_ms)
{
    struct pollfd pfd = {.fd = fd, .events = POLLIN};
    int ready = poll(&pfd, 1, timeout_ms);
    if (ready < 0) {
        return errno == EINTR ? 0 : -1;
    }
    if (ready == 0) {
        return 0;
    }
    if (!(pfd.revents & POLLIN)) {  /* hung up: nobody is talking, wait as if silent */
        /* in short naps: a stop signal that lands between the poll and the nap must
         * not wait out a whole link timeout */
        sleep_ms(timeout_ms < HUNG_UP_NAP_MS ? timeout_ms : HUNG_UP_NAP_MS);
        return 0;
    }
    ssize_t n = read(fd, buf, cap);
    if (n < 0) {
        if (errno == EIO || errno == EAGAIN || errno == EINTR) {
            sleep_ms(timeout_ms < 10 ? timeout_ms : 10);
            return 0;
        }
        return -1;
    }
    return (long)n;
}

/* CLOCK_MONOTONIC arrived with Linux 2.6; on the TS-5500's Linux 2.4 the clock ticks
 * since boot (times(): 10 ms at HZ=100) stand in. Neither steps with the wall clock. */
double gp_now_s(void)
{
    struct timespec ts;
    if (clock_gettime(CLOCK_MONOTONIC, &ts) == 0) {
        return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
    }
    struct tms unused;
    return (double)(unsigned long)times(&unused) / (double)sysconf(_SC_CLK_TCK);
}
