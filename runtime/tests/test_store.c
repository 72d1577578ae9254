/* Checkpoint and event log: a record's round trip, damaged and foreign records and
 * files refused, a torn record giving way to the one before, the journal's entries read
 * back in order up to the first torn or damaged one and emptied by a record, a full
 * journal, kill -9 at random moments, the atomic write leaving no temporary file, the
 * log's line format. */
#define _POSIX_C_SOURCE 200809L
#include <fcntl.h>
#include <signal.h>
#include <stddef.h>
#include <stdlib.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "gp_store.h"
#include "gp_test.h"

static char *temp_dir(void)
{
    static char path[64];
    strcpy(path, "/tmp/gp_store_XXXXXX");
    return mkdtemp(path);
}

static void remove_dir(const char *dir)
{
    char path[GP_PATH_MAX];
    gp_path_join(dir, "checkpoint", path);
    unlink(path);
    rmdir(dir);
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
    rt->sensors[9] = 14.5;
    rt->pilot.lo_m = 12.5;
    rt->pilot.hi_m = 16.5;
    rt->pilot.n_window = 2;
    rt->pilot.window[1] = (gp_reading){14.0, 11.5};
    rt->pilot.n_recent = 1;
    rt->pilot.recent_c[0] = 11.25;
    rt->pilot.halfcycle = 5;
    rt->route_resume[0] = 2;  /* the caller's waypoint, for its return */
    rt->reached_resume[0] = 70000;  /* and the waypoints it had reached: past a u16 */
    rt->route.reached = 1;  /* s2 flies no route: 0, or 1 for a list's last */
    rt->route.turn_from_rad = 1.25;  /* the heading a turn route turns from */
    /* its last turn, a climb; its heading commanded at 796 s; the pump owes 420 J */
    rt->envelope = (gp_envelope_memory){.last_turn_s = 796.0, .heading_rad = 2.5,
                                        .heading_s = 796.0, .ballast_cc = 230.0, .pump_s = 796.0, .pump_j = 420.0,
                                        .turned = 1, .climbing = 1, .headed = 1, .pumped = 1};
    rt->profile = 0;
    rt->last_command.tick = 81;
    rt->last_command.pitch_rad = 0.454f;
    rt->has_command = 1;
}

static const char *or_none(const char *problem) { return problem ? problem : "(none)"; }

void test_checkpoint_should_round_trip_what_is_in_use(void)
{
    static gp_runtime rt, back, expected;
    static uint8_t record[GP_CHECKPOINT_MAX_RECORD];
    sample_runtime(&rt);
    rt.sensors[5] = 3;  /* Fig. 2 does not read the altitude: not kept */
    size_t len = gp_checkpoint_encode(&gp_mission_table, &rt, 42, record);
    CHECK(len < 256);  /* the whole runtime state is 1.9 KiB */
    uint32_t seq = 0;
    CHECK(gp_checkpoint_decode(&gp_mission_table, record, len, &seq, &back) == NULL);
    CHECK_INT(seq, 42);
    expected = rt;
    expected.sensors[5] = NAN;
    CHECK(memcmp(&expected, &back, offsetof(gp_runtime, route)) == 0);
    CHECK_INT(back.route.next, 0);
    CHECK_INT(back.route.reached, 1);
    CHECK_NEAR(back.route.turn_from_rad, 1.25, 0);
    CHECK_INT(back.reached_resume[0], 70000);
    CHECK_NEAR(back.pilot.window[1].temp_c, 11.5, 0);
    CHECK(back.last_command.pitch_rad == rt.last_command.pitch_rad);
    /* the slot's bytes after the record do not matter: its length field says where it ends */
    memset(record + len, 0xA5, sizeof record - len);
    CHECK(gp_checkpoint_decode(&gp_mission_table, record, sizeof record, &seq, &back) == NULL);
}

void test_checkpoint_should_refuse_damaged_and_foreign_records(void)
{
    static gp_runtime rt, back;
    static uint8_t record[GP_CHECKPOINT_MAX_RECORD];
    uint32_t seq;
    sample_runtime(&rt);
    size_t len = gp_checkpoint_encode(&gp_mission_table, &rt, 3, record);
    CHECK_CONTAINS(or_none(gp_checkpoint_decode(&gp_mission_table, record, len - 1, &seq,
                                                &back)), "truncated");
    record[30] ^= 1;
    CHECK_CONTAINS(or_none(gp_checkpoint_decode(&gp_mission_table, record, len, &seq, &back)),
                   "checksum");
    CHECK_INT(back.machine.event_count, 0);  /* untouched by a refused record */
    memset(record, 0, sizeof record);  /* a slot never written */
    CHECK(gp_checkpoint_decode(&gp_mission_table, record, sizeof record, &seq, &back) != NULL);
    rt.route.reached = 2;  /* more waypoints reached than a route that does not loop has */
    len = gp_checkpoint_encode(&gp_mission_table, &rt, 3, record);
    CHECK_CONTAINS(or_none(gp_checkpoint_decode(&gp_mission_table, record, len, &seq, &back)),
                   "waypoints reached outside the route");
    rt.machine.state = 9;  /* well-formed but outside the mission: refused too */
    len = gp_checkpoint_encode(&gp_mission_table, &rt, 3, record);
    CHECK_CONTAINS(or_none(gp_checkpoint_decode(&gp_mission_table, record, len, &seq, &back)),
                   "outside the mission");
}

static void corrupt_byte(const char *dir, off_t offset)
{
    char path[GP_PATH_MAX];
    gp_path_join(dir, "checkpoint", path);
    int fd = open(path, O_RDWR);
    uint8_t byte = 0;
    CHECK(pread(fd, &byte, 1, offset) == 1);
    byte ^= 0x40;
    CHECK(pwrite(fd, &byte, 1, offset) == 1);
    close(fd);
}

static uint32_t reopen(const char *dir, const gp_mission *mission, int *resumed,
                       const char **problem)
{
    static gp_runtime rt;
    gp_checkpoint cp;
    gp_runtime_init(&rt);
    if (gp_checkpoint_open(&cp, dir, mission, &rt, resumed, problem) < 0) {
        return 0;
    }
    gp_checkpoint_close(&cp);
    return rt.machine.event_count;
}

void test_checkpoint_file_should_resume_from_the_newest_intact_record(void)
{
    static gp_runtime rt;
    char *dir = temp_dir();
    gp_checkpoint cp;
    int resumed = -1;
    const char *problem = NULL;
    CHECK(dir != NULL);
    sample_runtime(&rt);
    rt.machine.event_count = 0;
    CHECK_INT(gp_checkpoint_open(&cp, dir, &gp_mission_table, &rt, &resumed, &problem), 0);
    CHECK_INT(resumed, 0);  /* created, holding the state as it was */
    for (uint32_t count = 1; count <= 3; count++) {  /* records 2, 3, 4: slots 0, 1, 0 */
        rt.machine.event_count = count;
        CHECK_INT(gp_checkpoint_store(&cp, &gp_mission_table, &rt), 0);
    }
    gp_checkpoint_close(&cp);
    CHECK_INT(reopen(dir, &gp_mission_table, &resumed, &problem), 3);
    CHECK_INT(resumed, 1);

    /* a write torn in the newest record (slot 0): the one before it */
    corrupt_byte(dir, GP_CHECKPOINT_SLOT_BYTES + 20);
    CHECK_INT(reopen(dir, &gp_mission_table, &resumed, &problem), 2);
    /* the next record goes over the torn one, never over the one resumed from */
    gp_runtime_init(&rt);
    CHECK_INT(gp_checkpoint_open(&cp, dir, &gp_mission_table, &rt, &resumed, &problem), 0);
    rt.machine.event_count = 5;
    CHECK_INT(gp_checkpoint_store(&cp, &gp_mission_table, &rt), 0);
    gp_checkpoint_close(&cp);
    CHECK_INT(reopen(dir, &gp_mission_table, &resumed, &problem), 5);

    /* both records damaged, the header damaged, another mission: refused */
    corrupt_byte(dir, 2 * GP_CHECKPOINT_SLOT_BYTES + 20);
    corrupt_byte(dir, GP_CHECKPOINT_SLOT_BYTES + 20);
    CHECK_INT(reopen(dir, &gp_mission_table, &resumed, &problem), 0);
    CHECK_CONTAINS(or_none(problem), "checksum mismatch (damaged record)");
    corrupt_byte(dir, 40);
    reopen(dir, &gp_mission_table, &resumed, &problem);
    CHECK_CONTAINS(or_none(problem), "header");
    corrupt_byte(dir, 40);
    gp_mission other = gp_mission_table;
    other.hash = "0000000000000000000000000000000000000000000000000000000000000000";
    reopen(dir, &other, &resumed, &problem);
    CHECK_CONTAINS(or_none(problem), "another mission");
    remove_dir(dir);
}

static gp_checkpoint open_fresh(const char *dir, gp_runtime *rt)
{
    gp_checkpoint cp;
    int resumed;
    const char *problem;
    gp_runtime_init(rt);
    CHECK_INT(gp_checkpoint_open(&cp, dir, &gp_mission_table, rt, &resumed, &problem), 0);
    return cp;
}

/* A child that resumes from dir/checkpoint and stores counts as fast as it can. */
typedef void (*storing_child)(const char *dir, gp_checkpoint *cp, gp_runtime *rt,
                              int report_fd);

/* Fork `child`, kill it with SIGKILL after a random pause (0-5 ms: resuming, encoding,
 * writing or waiting for the disk). @return the last count it reported stored */
static uint32_t kill_at_random(const char *dir, unsigned *seed, storing_child child)
{
    int done_pipe[2];
    CHECK(pipe(done_pipe) == 0);
    pid_t pid = fork();
    if (pid == 0) {
        static gp_runtime rt;
        close(done_pipe[0]);
        gp_checkpoint cp = open_fresh(dir, &rt);
        child(dir, &cp, &rt, done_pipe[1]);
        _exit(1);
    }
    close(done_pipe[1]);
    struct timespec pause = {0, (long)(gp_test_random(seed) % 5000) * 1000L};
    nanosleep(&pause, NULL);
    kill(pid, SIGKILL);
    int status;
    waitpid(pid, &status, 0);
    CHECK(WIFSIGNALED(status));  /* not an early exit of its own */
    uint32_t reported = 0, count;
    while (read(done_pipe[0], &count, sizeof count) == sizeof count) {
        reported = count;
    }
    close(done_pipe[0]);
    return reported;
}

static void report(int fd, uint32_t count, int stored)
{
    if (stored != 0 || write(fd, &count, sizeof count) != sizeof count) {
        _exit(1);
    }
}

static void store_records(const char *dir, gp_checkpoint *cp, gp_runtime *rt, int report_fd)
{
    (void)dir;
    for (;;) {  /* every field follows from the count: a mixed record shows */
        uint32_t count = rt->machine.event_count + 1;
        rt->machine.event_count = count;
        rt->entry_time_s = count;
        rt->sensors[0] = 2.0 * count;
        rt->pilot.n_window = (uint8_t)(count % GP_TRACK_WINDOW);
        rt->pilot.window[rt->pilot.n_window / 2].depth_m = count;
        rt->last_command.tick = count;
        report(report_fd, count, gp_checkpoint_store(cp, &gp_mission_table, rt));
    }
}

/* The child is killed at a random moment, over and over: every time, the file opens
 * on an intact record, the last one the child said it had stored or the one it was
 * storing. */
void test_checkpoint_should_survive_kill_9_at_any_point(void)
{
    char *dir = temp_dir();
    unsigned seed = 2024;
    uint32_t previous = 0;  /* the count the child starts from: the last one resumed */
    CHECK(dir != NULL);
    for (int round = 0; round < 50; round++) {
        uint32_t stored = kill_at_random(dir, &seed, store_records);
        static gp_runtime back;
        gp_checkpoint cp = open_fresh(dir, &back);
        gp_checkpoint_close(&cp);
        uint32_t count = back.machine.event_count;
        uint32_t floor = stored > previous ? stored : previous;
        CHECK(count >= floor && count <= floor + 1);  /* at most one unreported store */
        previous = count;
        CHECK_NEAR(back.entry_time_s, count, 0);
        CHECK(count == 0 ? isnan(back.sensors[0]) : back.sensors[0] == 2.0 * count);
        CHECK_INT(back.pilot.n_window, count % GP_TRACK_WINDOW);
        CHECK_INT(back.last_command.tick, count);
    }
    remove_dir(dir);
}

/* The payloads the journal gives back after reopening, "len:first byte,..." */
static const char *journal_read_back(const char *dir)
{
    static char said[512];
    static gp_runtime rt;
    uint8_t payload[GP_MAX_PAYLOAD];
    gp_checkpoint cp = open_fresh(dir, &rt);
    said[0] = '\0';
    for (long len; (len = gp_journal_next(&cp, payload)) >= 0;) {
        size_t at = strlen(said);
        snprintf(said + at, sizeof said - at, "%s%ld:%d", at ? "," : "", len,
                 len > 0 ? payload[len - 1] : -1);
    }
    gp_checkpoint_close(&cp);
    return said;
}

static void append(gp_checkpoint *cp, size_t len, uint8_t last)
{
    uint8_t payload[GP_MAX_PAYLOAD];
    memset(payload, 0x5A, sizeof payload);
    if (len > 0) {
        payload[len - 1] = last;
    }
    CHECK_INT(gp_journal_append(cp, payload, len), 0);
}

void test_journal_should_give_back_its_entries_until_the_next_record(void)
{
    static gp_runtime rt;
    char *dir = temp_dir();
    CHECK(dir != NULL);
    gp_checkpoint cp = open_fresh(dir, &rt);
    append(&cp, 29, 1);  /* a Fig. 2 SENSORS payload */
    append(&cp, 0, 0);
    append(&cp, GP_MAX_PAYLOAD, 3);
    append(&cp, 6, 4);
    gp_checkpoint_close(&cp);
    CHECK(strcmp(journal_read_back(dir), "29:1,0:-1,240:3,6:4") == 0);

    /* a record holds what the entries said: they are not read again after it, and the
     * journal starts afresh */
    cp = open_fresh(dir, &rt);
    CHECK(gp_journal_next(&cp, (uint8_t[GP_MAX_PAYLOAD]){0}) == 29);
    rt.machine.event_count = 9;
    CHECK_INT(gp_checkpoint_store(&cp, &gp_mission_table, &rt), 0);
    gp_checkpoint_close(&cp);
    CHECK(strcmp(journal_read_back(dir), "") == 0);
    cp = open_fresh(dir, &rt);
    CHECK_INT(rt.machine.event_count, 9);
    append(&cp, 4, 7);
    gp_checkpoint_close(&cp);
    CHECK(strcmp(journal_read_back(dir), "4:7") == 0);
    CHECK_INT(gp_journal_append(&cp, (const uint8_t *)"", GP_MAX_PAYLOAD + 1), -1);
    remove_dir(dir);
}

/* Entry i of payloads of 5 bytes (6 words) starts at 24 i in the journal. */
#define JOURNAL_AT (3 * GP_CHECKPOINT_SLOT_BYTES)

void test_journal_should_end_at_a_torn_or_damaged_entry(void)
{
    static gp_runtime rt;
    char *dir = temp_dir();
    CHECK(dir != NULL);
    gp_checkpoint cp = open_fresh(dir, &rt);
    for (uint8_t i = 1; i <= 4; i++) {
        append(&cp, 5, i);
    }
    gp_checkpoint_close(&cp);
    corrupt_byte(dir, JOURNAL_AT + 2 * 24 + 9);  /* the third one's payload */
    CHECK(strcmp(journal_read_back(dir), "5:1,5:2") == 0);
    /* the next entry goes where reading stopped, over the damaged one */
    cp = open_fresh(dir, &rt);
    while (gp_journal_next(&cp, (uint8_t[GP_MAX_PAYLOAD]){0}) >= 0) {
    }
    append(&cp, 5, 9);
    gp_checkpoint_close(&cp);
    CHECK(strcmp(journal_read_back(dir), "5:1,5:2,5:9,5:4") == 0);
    /* torn: its sums never reached the disk; a damaged length; a damaged record number */
    corrupt_byte(dir, JOURNAL_AT + 3 * 24 + 20);
    CHECK(strcmp(journal_read_back(dir), "5:1,5:2,5:9") == 0);
    corrupt_byte(dir, JOURNAL_AT + 1 * 24 + 4);
    CHECK(strcmp(journal_read_back(dir), "5:1") == 0);
    corrupt_byte(dir, JOURNAL_AT + 0);
    CHECK(strcmp(journal_read_back(dir), "") == 0);
    remove_dir(dir);
}

void test_journal_should_ask_for_a_record_when_full(void)
{
    static gp_runtime rt;
    uint8_t payload[GP_MAX_PAYLOAD] = {0};
    char *dir = temp_dir();
    CHECK(dir != NULL);
    gp_checkpoint cp = open_fresh(dir, &rt);
    int appended = 0;
    while (gp_journal_append(&cp, payload, sizeof payload) == 0 && appended < 1000) {
        appended++;
    }
    CHECK_INT(appended, GP_JOURNAL_BYTES / GP_JOURNAL_MAX_ENTRY);
    CHECK_INT(gp_journal_append(&cp, payload, sizeof payload), 1);
    CHECK_INT(gp_checkpoint_store(&cp, &gp_mission_table, &rt), 0);
    CHECK_INT(gp_journal_append(&cp, payload, sizeof payload), 0);
    gp_checkpoint_close(&cp);
    /* the file was as large as it is ever going to be from the start */
    char path[GP_PATH_MAX];
    gp_path_join(dir, "checkpoint", path);
    int fd = open(path, O_RDONLY);
    CHECK(lseek(fd, 0, SEEK_END) == JOURNAL_AT + GP_JOURNAL_BYTES);
    close(fd);
    remove_dir(dir);
}

void test_checkpoint_should_refuse_an_older_format_and_another_journal_size(void)
{
    static gp_runtime rt;
    char *dir = temp_dir();
    int resumed;
    const char *problem = NULL;
    CHECK(dir != NULL);
    gp_checkpoint cp = open_fresh(dir, &rt);
    gp_checkpoint_close(&cp);
    char path[GP_PATH_MAX];
    gp_path_join(dir, "checkpoint", path);
    int fd = open(path, O_RDWR);
    uint32_t journal_bytes = 2 * GP_JOURNAL_BYTES;
    CHECK(pwrite(fd, &journal_bytes, 4, 76) == 4);
    reopen(dir, &gp_mission_table, &resumed, &problem);
    CHECK_CONTAINS(or_none(problem), "another build of the runtime");
    CHECK(pwrite(fd, "GPCKPT03", 8, 0) == 8);  /* the format before the journal */
    close(fd);
    reopen(dir, &gp_mission_table, &resumed, &problem);
    CHECK_CONTAINS(or_none(problem), "not a checkpoint of this runtime version");
    CHECK_INT(resumed, 1);
    remove_dir(dir);
}

/* The journal's count: a record's event count, then the entries after it. */
static uint32_t journaled_count(gp_checkpoint *cp, const gp_runtime *rt)
{
    uint8_t payload[GP_MAX_PAYLOAD];
    uint32_t count = rt->machine.event_count;
    CHECK_INT(count % 5, 0);
    for (long len; (len = gp_journal_next(cp, payload)) >= 0;) {
        uint32_t entry;
        CHECK_INT(len, 4);
        memcpy(&entry, payload, 4);
        CHECK_INT(entry, count + 1);  /* the counts after the record, in order */
        count = entry;
    }
    return count;
}

static void journal_counts(const char *dir, gp_checkpoint *cp, gp_runtime *rt, int report_fd)
{
    (void)dir;
    for (uint32_t count = journaled_count(cp, rt) + 1;; count++) {
        if (count % 5 == 0) {
            rt->machine.event_count = count;
            report(report_fd, count, gp_checkpoint_store(cp, &gp_mission_table, rt));
        } else {
            report(report_fd, count, gp_journal_append(cp, (const uint8_t *)&count, 4));
        }
    }
}

/* As above, with the journal: the child appends an entry (its count) each time and a
 * record every fifth; every time, the record and the entries after it say the last
 * count the child reported, or the one it was storing. */
void test_journal_should_survive_kill_9_at_any_point(void)
{
    char *dir = temp_dir();
    unsigned seed = 1871;
    uint32_t previous = 0;
    CHECK(dir != NULL);
    for (int round = 0; round < 50; round++) {
        uint32_t reported = kill_at_random(dir, &seed, journal_counts);
        static gp_runtime back;
        gp_checkpoint cp = open_fresh(dir, &back);
        uint32_t count = journaled_count(&cp, &back);
        gp_checkpoint_close(&cp);
        uint32_t floor = reported > previous ? reported : previous;
        CHECK(count >= floor && count <= floor + 1);
        previous = count;
    }
    remove_dir(dir);
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
