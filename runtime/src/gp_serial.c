/* POSIX serial I/O. A hung-up peer (pty master closed) reads as silence, so the
 * watchdog, not an error path, decides when to give control back. */
#define _POSIX_C_SOURCE 200809L
#include "gp_serial.h"

#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

#define WRITE_ATTEMPTS 1000

int gp_serial_open(const char *path)
{
    int fd = open(path, O_RDWR | O_NOCTTY);
    if (fd < 0) {
        return -1;
    }
    struct termios tio;
    if (tcgetattr(fd, &tio) < 0) {
        int saved = errno;
        close(fd);
        errno = saved;
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
        int saved = errno;
        close(fd);
        errno = saved;
        return -1;
    }
    return fd;
}

int gp_serial_write(int fd, const uint8_t *data, size_t len)
{
    for (int attempt = 0; len > 0 && attempt < WRITE_ATTEMPTS; attempt++) {
        ssize_t n = write(fd, data, len);
        if (n > 0) {
            data += n;
            len -= (size_t)n;
        } else if (n < 0 && errno != EINTR && errno != EAGAIN) {
            return -1;
        }
    }
    return len == 0 ? 0 : -1;
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
        sleep_ms(timeout_ms);
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

double gp_now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}
