/* The key file: 64 lowercase hex digits and a LF, mode 0600; anything else is refused
 * with a line that names the file. */
#define _POSIX_C_SOURCE 200809L
#include <fcntl.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <unistd.h>

#include "gp_key.h"
#include "gp_test.h"

#define KEY_HEX "000102030405060708090a0b0c0d0e0f101112131415161718191a1b1c1d1e1f"

static void write_key(const char *path, const char *text, mode_t mode)
{
    int fd = open(path, O_WRONLY | O_CREAT | O_TRUNC, 0600);
    if (fd < 0 || write(fd, text, strlen(text)) != (ssize_t)strlen(text)) {
        gp_test_fail(__FILE__, __LINE__, "cannot write the key file");
    }
    close(fd);
    chmod(path, mode);
}

void test_key_file_should_be_64_hex_digits_readable_by_its_owner_only(void)
{
    char dir[] = "/tmp/gp_key_XXXXXX", path[64], error[256];
    uint8_t key[GP_PLAN_KEY_BYTES];
    CHECK(mkdtemp(dir) != NULL);
    snprintf(path, sizeof path, "%s/vehicle.key", dir);
    CHECK_INT(gp_key_load(path, key, error, sizeof error), -1);
    CHECK_CONTAINS(error, "vehicle.key: cannot read the key file");
    write_key(path, KEY_HEX "\n", 0600);
    CHECK_INT(gp_key_load(path, key, error, sizeof error), 0);
    CHECK_INT(key[0], 0x00);
    CHECK_INT(key[31], 0x1f);
    write_key(path, KEY_HEX "\n", 0644);
    CHECK_INT(gp_key_load(path, key, error, sizeof error), -1);
    CHECK_CONTAINS(error, "may be read by others (mode 644): chmod 600 it");
    static const char *const bad[] = {KEY_HEX, KEY_HEX "\n\n", "00" KEY_HEX "\n",
                                      "0001020304050607080g0a0b0c0d0e0f101112131415161718191a1b1c1d1e1f\n",
                                      "000102030405060708090A0B0C0D0E0F101112131415161718191a1b1c1d1e1f\n"};
    for (unsigned i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        write_key(path, bad[i], 0600);
        CHECK_INT(gp_key_load(path, key, error, sizeof error), -1);
        CHECK_CONTAINS(error, "not a key file");
    }
    CHECK_INT(gp_key_load(dir, key, error, sizeof error), -1);
    CHECK_CONTAINS(error, "not a regular file");
    unlink(path);
    rmdir(dir);
}
