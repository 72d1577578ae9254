/* Command line of the runtime program. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gp_link.h"

#define USAGE "usage: PROG --device PATH|pty [--plan FILE] [--state-dir DIR] " \
              "[--clock-file PATH] [--suspend-file PATH] [--key FILE] " \
              "[--link-timeout-s S] [--retransmit-ms MS] [--naive-tracker]"

static int number(const char *text, double low, double high, double *out)
{
    char *end;
    double value = strtod(text, &end);
    if (end == text || *end != '\0' || !isfinite(value) || value < low || value > high) {
        return -1;
    }
    *out = value;
    return 0;
}

/* At most `cap - 1` bytes of `text` with every byte outside printable ASCII shown as '?':
 * an argument quoted in an error must not break its line or drive the terminal. */
static const char *shown(const char *text, char *out, size_t cap)
{
    size_t n = 0;
    for (; text[n] != '\0' && n + 1 < cap; n++) {
        unsigned char c = (unsigned char)text[n];
        out[n] = c >= 0x20 && c <= 0x7E ? (char)c : '?';
    }
    out[n] = '\0';
    return out;
}

int gp_args_parse(int argc, char **argv, gp_args *out, char *error, size_t cap)
{
    char quoted[65];
    *out = (gp_args){.link_timeout_s = GP_LINK_TIMEOUT_S, .retransmit_ms = GP_RETRANSMIT_MS};
    for (int i = 1; i < argc; i++) {
        const char *option = argv[i];
        const char *value = i + 1 < argc ? argv[i + 1] : NULL;
        double number_value;
        if (strcmp(option, "--naive-tracker") == 0) {
            out->naive_tracker = 1;
            continue;
        }
        int takes_value = strcmp(option, "--device") == 0 || strcmp(option, "--plan") == 0
            || strcmp(option, "--state-dir") == 0 || strcmp(option, "--link-timeout-s") == 0
            || strcmp(option, "--retransmit-ms") == 0 || strcmp(option, "--clock-file") == 0
            || strcmp(option, "--suspend-file") == 0 || strcmp(option, "--key") == 0;
        if (!takes_value) {
            snprintf(error, cap, "unknown argument '%s'; " USAGE,
                     shown(option, quoted, sizeof quoted));
            return -1;
        }
        if (value == NULL) {
            snprintf(error, cap, "%s needs a value; " USAGE, option);
            return -1;
        }
        i++;
        if (strcmp(option, "--device") == 0) {
            out->device = value;
        } else if (strcmp(option, "--plan") == 0) {
            out->plan_path = value;
        } else if (strcmp(option, "--state-dir") == 0) {
            out->state_dir = value;
        } else if (strcmp(option, "--clock-file") == 0) {
            out->clock_path = value;
        } else if (strcmp(option, "--key") == 0) {
            out->key_path = value;
        } else if (strcmp(option, "--suspend-file") == 0) {
            out->suspend_path = value;
        } else if (strcmp(option, "--link-timeout-s") == 0) {
            if (number(value, 0.001, 86400.0, &number_value) < 0) {
                snprintf(error, cap, "--link-timeout-s '%s' is not a number of seconds in "
                                     "0.001..86400", shown(value, quoted, 33));
                return -1;
            }
            out->link_timeout_s = number_value;
        } else {
            if (number(value, 1, 60000, &number_value) < 0 || number_value != floor(number_value)) {
                snprintf(error, cap, "--retransmit-ms '%s' is not a whole number of "
                                     "milliseconds in 1..60000", shown(value, quoted, 33));
                return -1;
            }
            out->retransmit_ms = (int)number_value;
        }
    }
    if (out->device == NULL) {
        snprintf(error, cap, "--device is required; " USAGE);
        return -1;
    }
    return 0;
}
