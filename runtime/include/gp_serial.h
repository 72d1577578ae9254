/**
 * @file gp_serial.h
 * @brief The serial line: termios raw 115200 8N1 without flow control, and a
 *        monotonic clock for the watchdog and retransmissions.
 */
#ifndef GP_SERIAL_H
#define GP_SERIAL_H

#include <stddef.h>
#include <stdint.h>

/** @brief Open `path` read-write in raw 115200 8N1; @return fd, or -1 with errno. */
int gp_serial_open(const char *path);

/**
 * @brief Create a pseudo-terminal in raw 115200 8N1 for a simulated science computer:
 *        the runtime keeps the master, the peer opens `peer_path` (its slave).
 * @return the master's fd, or -1 with errno
 */
int gp_serial_open_pty(char *peer_path, size_t cap);

/** What arrives while lingering: `len` bytes for the caller (`ctx` is its own), which
 *  may decode them in place. */
typedef void (*gp_serial_bytes_fn)(void *ctx, uint8_t *bytes, size_t len);

/**
 * @brief Before closing a pty master: wait (at most `max_s`) for the peer to close its
 *        end, since closing the master discards whatever the peer has not yet read;
 *        what the peer sends meanwhile goes to `on_bytes` (NULL: dropped).
 */
void gp_serial_linger(int fd, double max_s, gp_serial_bytes_fn on_bytes, void *ctx);

/**
 * @brief Write all bytes, waiting for room on a full line at most 1 s in all.
 * @return 0, or -1: an error, the bound passed (the peer stopped reading), or a signal
 *         arrived while waiting (the caller's loop looks at its stop signals)
 */
int gp_serial_write(int fd, const uint8_t *data, size_t len);

/** @brief Wait (at most `max_s`, less if a signal arrives) until the bytes written have
 *         left the line's output queue. */
void gp_serial_drain(int fd, double max_s);

/**
 * @brief Wait up to `timeout_ms` for bytes and read at most `cap`; on a line whose peer
 *        hung up, wait at most 50 ms (the caller's loop checks its signals and watchdog).
 * @return bytes read (0: none within the timeout or the peer hung up), -1 on error
 */
long gp_serial_read(int fd, uint8_t *buf, size_t cap, int timeout_ms);

/** @brief Monotonic time [s]. */
double gp_now_s(void);

#endif /* GP_SERIAL_H */
