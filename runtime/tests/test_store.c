/* Checkpoint and event log: a round trip, damaged and foreign checkpoints refused,
 * the atomic write leaving no temporary file, the log's line format. */
#define _POSIX_C_SOURCE 200809L
#include <fcntl.h>
#include <stdlib.h>
#include <unistd.h>

#include "gp_store.h"
#include "gp_test.h"

static char *temp_dir(void)
{
    static char path[64];
    strcpy(path, "/tmp/gp_store_XXXXXX");
    return mkdtemp(path);
}

static void sample_runtime(gp_runtime *rt)
{
    gp_runtime_init(rt);
    rt->started = 1;
    rt->machine.state = 1;
    rt->machine.depth = 1;
    rt->machine.stack[0] = 0;
    rt->machine.event_count = 7;
    rt->entry_time_s = 500;
    rt->sensors[0] = 812;
    rt->pilot.lo_m = 12.5;
    rt->pilot.hi_m = 16.5;
    rt->pilot.n_window = 2;
    rt->pilot.window[1] = (gp_reading){14.0, 11.5};
    rt->profile = 0;
    rt->last_command.tick = 81;
    rt->has_command = 1;
}

void test_checkpoint_should_round_trip(void)
{
    static gp_runtime rt, back;
    static uint8_t buf[GP_CHECKPOINT_SIZE];
    sample_runtime(&rt);
    gp_checkpoint_encode(&gp_mission_table, &rt, buf);
    CHECK(gp_checkpoint_decode(&gp_mission_table, buf, sizeof buf, &back) == NULL);
    CHECK(memcmp(&rt, &back, sizeof rt) == 0);
    CHECK_INT(back.machine.state, 1);
    CHECK_NEAR(back.pilot.window[1].temp_c, 11.5, 0);
    CHECK(isnan(back.sensors[5]));
}

void test_checkpoint_should_refuse_damaged_and_foreign_files(void)
{
    static gp_runtime rt, back;
    static uint8_t buf[GP_CHECKPOINT_SIZE];
    sample_runtime(&rt);
    gp_checkpoint_encode(&gp_mission_table, &rt, buf);
    CHECK_CONTAINS(gp_checkpoint_decode(&gp_mission_table, buf, sizeof buf - 1, &back),
                   "truncated");
    buf[100] ^= 1;
    CHECK_CONTAINS(gp_checkpoint_decode(&gp_mission_table, buf, sizeof buf, &back), "checksum");
    buf[100] ^= 1;
    gp_mission other = gp_mission_table;
    other.hash = "0000000000000000000000000000000000000000000000000000000000000000";
    CHECK_CONTAINS(gp_checkpoint_decode(&other, buf, sizeof buf, &back), "another mission");
    CHECK_CONTAINS(gp_checkpoint_decode(&gp_mission_table, (const uint8_t *)"GPPLAN 1", 8,
                                        &back), "not a checkpoint");
    rt.machine.state = 9;  /* well-formed but outside the mission: refused too */
    gp_checkpoint_encode(&gp_mission_table, &rt, buf);
    CHECK_CONTAINS(gp_checkpoint_decode(&gp_mission_table, buf, sizeof buf, &back),
                   "outside the mission");
}

void test_atomic_write_should_replace_the_file_whole(void)
{
    char *dir = temp_dir();
    char path[GP_PATH_MAX], tmp[GP_PATH_MAX + 8], buf[64];
    CHECK(dir != NULL);
    gp_path_join(dir, "checkpoint", path);
    CHECK_INT(gp_write_atomically(dir, "checkpoint", "first version", 13), 0);
    CHECK_INT(gp_write_atomically(dir, "checkpoint", "second", 6), 0);
    CHECK_INT(gp_read_file(path, buf, sizeof buf), 6);
    CHECK(memcmp(buf, "second", 6) == 0);
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    CHECK(access(tmp, F_OK) != 0);
    CHECK_INT(gp_read_file(path, buf, 3), -2);  /* larger than the buffer */
    unlink(path);
    CHECK_INT(gp_read_file(path, buf, sizeof buf), -1);
    CHECK_INT(gp_write_atomically("/nonexistent/dir", "checkpoint", "x", 1), -1);
    rmdir(dir);
}

void test_event_log_should_append_one_line_per_transition(void)
{
    char *dir = temp_dir();
    char path[GP_PATH_MAX], buf[256];
    gp_path_join(dir, "events.log", path);
    int fd = open(path, O_WRONLY | O_CREAT | O_APPEND, 0644);
    CHECK(fd >= 0);
    CHECK_INT(gp_events_append(fd, &gp_mission_table, 0, "start", 0xFF, 0, 0), 0);
    CHECK_INT(gp_events_append(fd, &gp_mission_table, 500, "call", 0, 1, 1), 0);
    CHECK_INT(gp_events_append(fd, &gp_mission_table, 2500.25, "exit", 2, 0xFF, 0), 0);
    close(fd);
    long n = gp_read_file(path, buf, sizeof buf - 1);
    CHECK(n > 0);
    buf[n > 0 ? n : 0] = '\0';
    CHECK(strcmp(buf, "0 start - s1 0\n500 call s1 s2 1\n2500.25 exit s3 - 0\n") == 0);
    unlink(path);
    rmdir(dir);
}
