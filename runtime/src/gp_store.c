/* Crash safety: a checkpoint is either the old or the new one (rename is atomic),
 * and its CRC catches a file damaged outside the runtime. */
#define _POSIX_C_SOURCE 200809L
#include "gp_store.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "gp_crc.h"

static void put_u32(uint8_t *p, uint32_t v)
{
    for (int i = 0; i < 4; i++) {
        p[i] = (uint8_t)(v >> (8 * i));
    }
}

static uint32_t get_u32(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}

void gp_checkpoint_encode(const gp_mission *mission, const gp_runtime *rt, uint8_t *buf)
{
    memcpy(buf, GP_CHECKPOINT_MAGIC, 8);
    memset(buf + 8, 0, 64);
    if (mission->hash) {
        memcpy(buf + 8, mission->hash, strnlen(mission->hash, 64));
    }
    put_u32(buf + 72, (uint32_t)GP_CHECKPOINT_STATE_SIZE);
    memcpy(buf + 76, rt, GP_CHECKPOINT_STATE_SIZE);
    size_t body = 76 + GP_CHECKPOINT_STATE_SIZE;
    put_u32(buf + body, gp_crc32(0, buf, body));
}

const char *gp_checkpoint_decode(const gp_mission *mission, const uint8_t *buf, size_t len,
                                 gp_runtime *rt)
{
    size_t body = 76 + GP_CHECKPOINT_STATE_SIZE;
    if (len < 8 || memcmp(buf, GP_CHECKPOINT_MAGIC, 8) != 0) {
        return "not a checkpoint of this runtime version";
    }
    if (len != GP_CHECKPOINT_SIZE || get_u32(buf + 72) != GP_CHECKPOINT_STATE_SIZE) {
        return "truncated, or written by another build of the runtime";
    }
    if (gp_crc32(0, buf, body) != get_u32(buf + body)) {
        return "checksum mismatch (damaged file)";
    }
    char hash[64] = {0};
    if (mission->hash) {
        memcpy(hash, mission->hash, strnlen(mission->hash, 64));
    }
    if (memcmp(buf + 8, hash, 64) != 0) {
        return "written by another mission";
    }
    static gp_runtime loaded;  /* 5 KiB: static, not on a small board's stack */
    memset(&loaded, 0, sizeof loaded);
    memcpy(&loaded, buf + 76, GP_CHECKPOINT_STATE_SIZE);
    if (loaded.machine.state != GP_EXITED && loaded.machine.state >= mission->n_states) {
        return "state index outside the mission";
    }
    if (loaded.machine.depth > mission->stack_depth || loaded.pilot.n_window > GP_TRACK_WINDOW
        || loaded.pilot.n_recent > 3 || loaded.route.n_waypoints > GP_MAX_SWEEP_WAYPOINTS
        || loaded.route.next >= GP_MAX_SWEEP_WAYPOINTS
        || (loaded.profile >= GP_MAX_PROFILE_ALTERNATIVES && loaded.profile != GP_NO_PROFILE)) {
        return "counts outside their bounds";
    }
    for (int i = 0; i < loaded.machine.depth; i++) {
        if (loaded.machine.stack[i] >= mission->n_states) {
            return "stacked state outside the mission";
        }
    }
    if (loaded.machine.state < mission->n_states) {
        gp_route_fill(&loaded.route, &mission->states[loaded.machine.state].route);
        if (loaded.route.next >= loaded.route.n_waypoints && loaded.route.next > 0) {
            return "waypoint index outside the route";
        }
    }
    *rt = loaded;
    return NULL;
}

int gp_path_join(const char *dir, const char *name, char *out)
{
    int n = snprintf(out, GP_PATH_MAX, "%s/%s", dir, name);
    return (n < 0 || n >= GP_PATH_MAX) ? -1 : 0;
}

static int write_all(int fd, const void *data, size_t len)
{
    const uint8_t *p = data;
    while (len > 0) {
        ssize_t n = write(fd, p, len);
        if (n < 0 && errno == EINTR) {
            continue;
        }
        if (n <= 0) {
            return -1;
        }
        p += n;
        len -= (size_t)n;
    }
    return 0;
}

int gp_write_atomically(const char *dir, const char *name, const void *data, size_t len)
{
    char path[GP_PATH_MAX], tmp[GP_PATH_MAX + 8];
    if (gp_path_join(dir, name, path) < 0) {
        errno = ENAMETOOLONG;
        return -1;
    }
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    int fd = open(tmp, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd < 0) {
        return -1;
    }
    if (write_all(fd, data, len) < 0 || fsync(fd) < 0) {
        int saved = errno;
        close(fd);
        unlink(tmp);
        errno = saved;
        return -1;
    }
    if (close(fd) < 0 || rename(tmp, path) < 0) {
        return -1;
    }
    int dir_fd = open(dir, O_RDONLY);
    if (dir_fd >= 0) {  /* make the rename itself durable */
        fsync(dir_fd);
        close(dir_fd);
    }
    return 0;
}

long gp_read_file(const char *path, void *buf, size_t cap)
{
    int fd = open(path, O_RDONLY);
    if (fd < 0) {
        return errno == ENOENT ? -1 : -2;
    }
    size_t total = 0;
    for (;;) {
        if (total == cap) {  /* full: one more byte means too large */
            char extra;
            ssize_t n = read(fd, &extra, 1);
            close(fd);
            return n == 0 ? (long)total : -2;
        }
        ssize_t n = read(fd, (uint8_t *)buf + total, cap - total);
        if (n < 0 && errno == EINTR) {
            continue;
        }
        if (n < 0) {
            close(fd);
            return -2;
        }
        if (n == 0) {
            break;
        }
        total += (size_t)n;
    }
    close(fd);
    return (long)total;
}

const char *gp_transition_name(uint8_t kind)
{
    static const char *const names[] = {"none", "start", "goto", "call", "return", "exit"};
    return kind < sizeof names / sizeof names[0] ? names[kind] : "?";
}

static const char *state_name(const gp_mission *mission, uint8_t index)
{
    return index < mission->n_states ? mission->states[index].name : "-";
}

int gp_events_append(int fd, const gp_mission *mission, double time_s, const char *kind,
                     uint8_t from, uint8_t to, uint8_t depth)
{
    char line[256];
    int n = snprintf(line, sizeof line, "%.17g %s %.64s %.64s %u\n", time_s, kind,
                     state_name(mission, from), state_name(mission, to), (unsigned)depth);
    if (n < 0 || (size_t)n >= sizeof line) {
        return -1;
    }
    return (write_all(fd, line, (size_t)n) < 0 || fsync(fd) < 0) ? -1 : 0;
}
