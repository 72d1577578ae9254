/* libFuzzer harness for the runtime's command line (gp_args_parse): the input, split at
 * NUL bytes, is the argument list after the program name. A refusal must say why in
 * one terminated line; an accepted line must have a device and values in their ranges.
 */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "gp_link.h"

#define MAX_ARGS 32

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static char text[4096];
    char *argv[MAX_ARGS + 2] = {"mission"};
    int argc = 1;
    if (size >= sizeof text) {
        size = sizeof text - 1;
    }
    memcpy(text, data, size);
    text[size] = '\0';
    for (size_t start = 0; start <= size && argc <= MAX_ARGS; argc++) {
        argv[argc] = text + start;
        start += strlen(text + start) + 1;
    }
    argv[argc] = NULL;

    gp_args args;
    char error[256];
    memset(error, 0, sizeof error);
    if (gp_args_parse(argc, argv, &args, error, sizeof error) == 0) {
        if (args.device == NULL || !(args.link_timeout_s >= 0.001 && args.link_timeout_s <= 86400)
            || args.retransmit_ms < 1 || args.retransmit_ms > 60000) {
            abort();
        }
    } else if (error[0] == '\0' || strchr(error, '\n') != NULL) {
        abort();
    }
    return 0;
}
