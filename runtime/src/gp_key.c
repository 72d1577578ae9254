/* The plan key: read once at start-up from a file only its owner may read, as ssh does
 * with private keys, so that a key left readable by everyone is noticed on the bench
 * rather than after a deployment. */
#define _POSIX_C_SOURCE 200809L
#include "gp_key.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static int hex_value(char c)
{
    return c >= '0' && c <= '9' ? c - '0' : c >= 'a' && c <= 'f' ? c - 'a' + 10 : -1;
}

int gp_key_load(const char *path, uint8_t key[GP_PLAN_KEY_BYTES], char *error, size_t cap)
{
    char text[GP_KEY_FILE_BYTES + 1];
    struct stat st;
    int fd = open(path, O_RDONLY | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) {
        snprintf(error, cap, "%.200s: cannot read the key file: %s", path, strerror(errno));
        return -1;
    }
    if (fstat(fd, &st) < 0 || !S_ISREG(st.st_mode)) {
        snprintf(error, cap, "%.200s: the key file is not a regular file", path);
        close(fd);
        return -1;
    }
    if (st.st_mode & (S_IRWXG | S_IRWXO)) {
        snprintf(error, cap, "%.200s: the key file may be read by others (mode %03o): "
                 "chmod 600 it", path, (unsigned)(st.st_mode & 0777));
        close(fd);
        return -1;
    }
    ssize_t n = read(fd, text, sizeof text);
    close(fd);
    int ok = n == GP_KEY_FILE_BYTES && text[GP_KEY_FILE_BYTES - 1] == '\n';
    for (int i = 0; ok && i < GP_PLAN_KEY_BYTES; i++) {
        int high = hex_value(text[2 * i]), low = hex_value(text[2 * i + 1]);
        ok = high >= 0 && low >= 0;
        key[i] = (uint8_t)(ok ? high << 4 | low : 0);
    }
    if (!ok) {
        memset(key, 0, GP_PLAN_KEY_BYTES);
        snprintf(error, cap, "%.200s: not a key file (%d lowercase hex digits and a LF; "
                 "gliderplan keygen writes one)", path, 2 * GP_PLAN_KEY_BYTES);
        return -1;
    }
    return 0;
}
