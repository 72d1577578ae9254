/**
 * @file gp_link.h
 * @brief The runtime program: command line, start-up (plan, checkpoint), and the
 *        link with the science computer (HELLO, SENSORS -> COMMAND, NAK,
 *        PLAN, watchdog RELEASE).
 */
#ifndef GP_LINK_H
#define GP_LINK_H

#include <stddef.h>

#include "gp_contract.h"  /* the exit statuses, gp_exit_status */

/** `--device pty`: create a pseudo-terminal and print its peer's path on stdout. */
#define GP_DEVICE_PTY "pty"

typedef struct {
    const char *device;          /**< serial device path, or GP_DEVICE_PTY */
    const char *plan_path;       /**< NULL: no plan */
    const char *state_dir;       /**< NULL: no checkpoint, no event log */
    const char *clock_path;      /**< NULL: the clock is left alone; else gets kHz */
    const char *key_path;        /**< NULL: no key, plans over the link are refused */
    const char *suspend_path;    /**< NULL: never sleeps; else gets "mem" between ticks */
    double link_timeout_s;       /**< default GP_LINK_TIMEOUT_S */
    int retransmit_ms;           /**< default GP_RETRANSMIT_MS */
    int naive_tracker;
} gp_args;

/**
 * @brief Parse the command line.
 * @param error on failure, a one-line message (capacity `cap`)
 * @return 0, or -1
 */
int gp_args_parse(int argc, char **argv, gp_args *out, char *error, size_t cap);

/** @brief Run the program; @return its exit status. */
int gp_main(int argc, char **argv);

#endif /* GP_LINK_H */
