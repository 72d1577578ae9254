/* Crash safety: the checkpoint's records alternate between two slots, so a write torn
 * by a crash never touches the newest intact record, and each record's CRC-32 tells a
 * torn one apart; the file itself comes into being whole (rename is atomic). Between
 * records, each tick appends a journal entry of a few words, which a word-wise checksum
 * guards: the CRC-32 of a whole record every tick cost more than the tick's step. */
#define _POSIX_C_SOURCE 200809L
#include "gp_store.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "gp_crc.h"

/* ---- records ------------------------------------------------------------------ */

/* Fields in the board's own byte order (all three targets are little-endian): a record
 * is read back only by the build that wrote it, which the header's slot size and the
 * mission hash check. */
typedef struct {
    uint8_t *at;
} writer;

static void put(writer *w, const void *value, size_t n)
{
    memcpy(w->at, value, n);
    w->at += n;
}

typedef struct {
    const uint8_t *at, *end;
    int short_read;  /* a field ran past the record */
} reader;

static void get(reader *r, void *value, size_t n)
{
    if ((size_t)(r->end - r->at) < n) {
        r->short_read = 1;
        memset(value, 0, n);
        return;
    }
    memcpy(value, r->at, n);
    r->at += n;
}

size_t gp_checkpoint_encode(const gp_mission *mission, const gp_runtime *rt, uint32_t seq,
                            uint8_t *record)
{
    writer w = {record + 6};  /* after the sequence number and the length */
    const gp_machine *m = &rt->machine;
    const gp_pilot *pilot = &rt->pilot;
    uint8_t depth = m->depth <= GP_MAX_STACK_DEPTH ? m->depth : GP_MAX_STACK_DEPTH;
    uint8_t n_vars = mission->n_vars <= GP_MAX_VARIABLES ? mission->n_vars : GP_MAX_VARIABLES;
    uint8_t n_window = pilot->n_window <= GP_TRACK_WINDOW ? pilot->n_window : GP_TRACK_WINDOW;
    uint8_t n_recent = pilot->n_recent <= 3 ? pilot->n_recent : 3;
    const uint8_t head[6] = {rt->started, m->state, depth, n_vars, rt->profile,
                             rt->has_command};
    put(&w, head, sizeof head);
    put(&w, m->stack, depth);
    put(&w, rt->route_resume, 2u * depth);
    put(&w, rt->reached_resume, 4u * depth);
    put(&w, &m->event_count, 4);
    put(&w, &rt->events_log_bytes, 4);
    put(&w, &rt->entry_time_s, 8);
    put(&w, m->vars, 8u * n_vars);
    for (int i = 0; i < GP_N_SENSORS; i++) {  /* only what the mission reads */
        if ((mission->read_mask >> i) & 1u) {
            put(&w, &rt->sensors[i], 8);
        }
    }
    const uint8_t pilot_head[4] = {pilot->leg, pilot->detected, n_window, n_recent};
    put(&w, pilot_head, sizeof pilot_head);
    put(&w, &pilot->halfcycle, 4);
    put(&w, &pilot->lo_m, 8);
    put(&w, &pilot->hi_m, 8);
    put(&w, &pilot->previous_c, 8);
    put(&w, pilot->recent_c, 8u * n_recent);
    put(&w, pilot->window, sizeof pilot->window[0] * n_window);
    put(&w, &rt->route.next, 2);
    put(&w, &rt->route.reached, 4);
    put(&w, &rt->route.turn_from_rad, 8);
    const gp_envelope_memory *guard = &rt->envelope;
    const uint8_t envelope_head[5] = {guard->turned, guard->climbing, guard->held,
                                      guard->headed, guard->pumped};
    put(&w, envelope_head, sizeof envelope_head);
    const double envelope_figures[GP_ENVELOPE_MEMORY_FIGURES] = {
        guard->last_turn_s, guard->heading_rad, guard->heading_s, guard->ballast_cc,
        guard->pump_s, guard->pump_j};
    put(&w, envelope_figures, sizeof envelope_figures);
    uint8_t *command_len = w.at++;  /* the last COMMAND as the link sends it whole */
    *command_len = (uint8_t)gp_command_pack(&rt->last_command, NULL, w.at);
    w.at += *command_len;
    size_t len = (size_t)(w.at - record) + 4;
    memcpy(record, &seq, 4);
    uint16_t len16 = (uint16_t)len;
    memcpy(record + 4, &len16, 2);
    uint32_t crc = gp_crc32(0, record, len - 4);
    memcpy(record + len - 4, &crc, 4);
    return len;
}

const char *gp_checkpoint_decode(const gp_mission *mission, const uint8_t *record, size_t len,
                                 uint32_t *seq, gp_runtime *rt)
{
    uint16_t size;
    if (len < 6 + 4) {
        return "record truncated";
    }
    memcpy(&size, record + 4, 2);
    if (size < 6 + 4 || size > len || size > GP_CHECKPOINT_MAX_RECORD) {
        return "record truncated, or its length damaged";
    }
    uint32_t crc;
    memcpy(&crc, record + size - 4, 4);
    if (gp_crc32(0, record, size - 4u) != crc) {
        return "checksum mismatch (damaged record)";
    }
    static gp_runtime loaded;  /* 5 KiB: static, not on a small board's stack */
    gp_runtime_init(&loaded);
    gp_machine *m = &loaded.machine;
    gp_pilot *pilot = &loaded.pilot;
    reader r = {record + 6, record + size - 4, 0};
    uint8_t head[6];
    get(&r, head, sizeof head);
    loaded.started = head[0];
    m->state = head[1];
    m->depth = head[2];
    loaded.profile = head[4];
    loaded.has_command = head[5];
    if (head[3] != mission->n_vars || m->depth > mission->stack_depth
        || m->depth > GP_MAX_STACK_DEPTH) {
        return "counts outside their bounds";
    }
    get(&r, m->stack, m->depth);
    get(&r, loaded.route_resume, 2u * m->depth);
    get(&r, loaded.reached_resume, 4u * m->depth);
    get(&r, &m->event_count, 4);
    get(&r, &loaded.events_log_bytes, 4);
    get(&r, &loaded.entry_time_s, 8);
    get(&r, m->vars, 8u * mission->n_vars);
    for (int i = 0; i < GP_N_SENSORS; i++) {
        if ((mission->read_mask >> i) & 1u) {
            get(&r, &loaded.sensors[i], 8);
        }
    }
    uint8_t pilot_head[4];
    get(&r, pilot_head, sizeof pilot_head);
    get(&r, &pilot->halfcycle, 4);
    pilot->leg = pilot_head[0];
    pilot->detected = pilot_head[1];
    pilot->n_window = pilot_head[2];
    pilot->n_recent = pilot_head[3];
    if (pilot->n_window > GP_TRACK_WINDOW || pilot->n_recent > 3) {
        return "counts outside their bounds";
    }
    get(&r, &pilot->lo_m, 8);
    get(&r, &pilot->hi_m, 8);
    get(&r, &pilot->previous_c, 8);
    get(&r, pilot->recent_c, 8u * pilot->n_recent);
    get(&r, pilot->window, sizeof pilot->window[0] * pilot->n_window);
    get(&r, &loaded.route.next, 2);
    get(&r, &loaded.route.reached, 4);
    get(&r, &loaded.route.turn_from_rad, 8);
    uint8_t envelope_head[5];
    double envelope_figures[GP_ENVELOPE_MEMORY_FIGURES];
    get(&r, envelope_head, sizeof envelope_head);
    get(&r, envelope_figures, sizeof envelope_figures);
    gp_envelope_memory *guard = &loaded.envelope;
    guard->turned = envelope_head[0];
    guard->climbing = envelope_head[1];
    guard->held = envelope_head[2];
    guard->headed = envelope_head[3];
    guard->pumped = envelope_head[4];
    guard->last_turn_s = envelope_figures[0];
    guard->heading_rad = envelope_figures[1];
    guard->heading_s = envelope_figures[2];
    guard->ballast_cc = envelope_figures[3];
    guard->pump_s = envelope_figures[4];
    guard->pump_j = envelope_figures[5];
    uint8_t command_len;
    get(&r, &command_len, 1);
    gp_frame command = {GP_MSG_COMMAND, 0, 0, command_len, r.at};
    if (r.short_read || command_len != r.end - r.at
        || gp_command_unpack(&command, NULL, &loaded.last_command) != GP_FRAME_OK) {
        return "record length disagrees with its counts";
    }
    if (m->state != GP_EXITED && m->state >= mission->n_states) {
        return "state index outside the mission";
    }
    if (loaded.profile >= GP_MAX_PROFILE_ALTERNATIVES && loaded.profile != GP_NO_PROFILE) {
        return "counts outside their bounds";
    }
    for (int i = 0; i < m->depth; i++) {
        if (m->stack[i] >= mission->n_states) {
            return "stacked state outside the mission";
        }
    }
    if (m->state < mission->n_states) {
        const gp_route *route = &mission->states[m->state].route;
        gp_route_fill(&loaded.route, route);
        if (loaded.route.next >= loaded.route.n_waypoints && loaded.route.next > 0) {
            return "waypoint index outside the route";
        }
        /* a list that does not loop has reached its waypoint index, or one more (its last) */
        uint32_t reached = loaded.route.reached, next = loaded.route.next;
        if (route->kind != GP_ROUTE_GOTO_LIST && (reached < next || reached > next + 1u)) {
            return "waypoints reached outside the route";
        }
    }
    memcpy(seq, record, 4);
    *rt = loaded;
    return NULL;
}

/* ---- the checkpoint file --------------------------------------------------------- */

static uint8_t record_buf[GP_CHECKPOINT_MAX_RECORD];

static void encode_header(const gp_mission *mission, uint8_t *header)
{
    const uint32_t sizes[2] = {GP_CHECKPOINT_SLOT_BYTES, GP_JOURNAL_BYTES};
    memcpy(header, GP_CHECKPOINT_MAGIC, 8);
    memset(header + 8, 0, 64);
    if (mission->hash) {
        memcpy(header + 8, mission->hash, strnlen(mission->hash, 64));
    }
    memcpy(header + 72, sizes, 8);
    uint32_t crc = gp_crc32(0, header, 80);
    memcpy(header + 80, &crc, 4);
}

static const char *check_header(const gp_mission *mission, const uint8_t *header, long len)
{
    uint8_t expected[GP_CHECKPOINT_HEADER_BYTES];
    if (len < 8 || memcmp(header, GP_CHECKPOINT_MAGIC, 8) != 0) {
        return "not a checkpoint of this runtime version";
    }
    encode_header(mission, expected);
    if (len < GP_CHECKPOINT_HEADER_BYTES || memcmp(header + 72, expected + 72, 8) != 0) {
        return "truncated, or written by another build of the runtime";
    }
    uint32_t crc;
    memcpy(&crc, header + 80, 4);
    if (gp_crc32(0, header, 80) != crc) {
        return "checksum mismatch in its header (damaged file)";
    }
    if (memcmp(header + 8, expected + 8, 64) != 0) {
        return "written by another mission";
    }
    return NULL;
}

static off_t slot_offset(uint32_t seq)
{
    return (off_t)GP_CHECKPOINT_SLOT_BYTES * (1 + (seq & 1u));
}

#define JOURNAL_OFFSET ((off_t)GP_CHECKPOINT_SLOT_BYTES * 3)  /* after the header and slots */
#define CHECKPOINT_FILE_BYTES (JOURNAL_OFFSET + GP_JOURNAL_BYTES)

static ssize_t read_at(int fd, void *buf, size_t len, off_t offset)
{
    ssize_t n;
    do {
        n = pread(fd, buf, len, offset);
    } while (n < 0 && errno == EINTR);
    return n;
}

/* All of `data` at `offset`, or at the end with a negative offset (the event log). */
static int write_at(int fd, const void *data, size_t len, off_t offset)
{
    const uint8_t *p = data;
    while (len > 0) {
        ssize_t n = offset < 0 ? write(fd, p, len) : pwrite(fd, p, len, offset);
        if (n < 0 && errno == EINTR) {
            continue;
        }
        if (n <= 0) {
            return -1;
        }
        p += n;
        len -= (size_t)n;
        offset = offset < 0 ? offset : offset + n;
    }
    return 0;
}

/* Pieces of a file written whole: temporary file, fsync, rename, fsync of the
 * directory. What lies between the pieces reads as zeros. */
typedef struct {
    off_t offset;
    const void *data;
    size_t len;
} piece;

/* @param size the file's size, its blocks reserved now so that no later write in it finds
 *        the disk full (a file system without fallocate: the size only); 0: the pieces' */
static int replace_file(const char *dir, const char *name, const piece *pieces, int n_pieces,
                        off_t size)
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
    int failed = 0;
    for (int i = 0; i < n_pieces && !failed; i++) {
        failed = write_at(fd, pieces[i].data, pieces[i].len, pieces[i].offset) < 0;
    }
    int error = failed || size == 0 ? 0 : posix_fallocate(fd, 0, size);
    if (error == EOPNOTSUPP || error == EINVAL) {
        error = ftruncate(fd, size) < 0 ? errno : 0;
    }
    if (error) {
        errno = error;
        failed = 1;
    }
    if (failed || fsync(fd) < 0) {
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

int gp_write_atomically(const char *dir, const char *name, const void *data, size_t len)
{
    const piece whole = {0, data, len};
    return replace_file(dir, name, &whole, 1, 0);
}

/* The file as it comes into being: the header, and `rt` as record 1 in slot 1; slot 0
 * holds no record yet (zeros fail the CRC), the journal no entry (zeros name no record). */
static int create_checkpoint(const char *dir, const gp_mission *mission, const gp_runtime *rt)
{
    uint8_t header[GP_CHECKPOINT_HEADER_BYTES];
    encode_header(mission, header);
    size_t len = gp_checkpoint_encode(mission, rt, 1, record_buf);
    const piece pieces[] = {{0, header, sizeof header}, {slot_offset(1), record_buf, len}};
    return replace_file(dir, "checkpoint", pieces, 2, CHECKPOINT_FILE_BYTES);
}

/* The newest intact record of an open file into `rt`; NULL, or what is wrong. */
static const char *load_newest(int fd, const gp_mission *mission, gp_runtime *rt,
                               uint32_t *seq)
{
    uint8_t header[GP_CHECKPOINT_HEADER_BYTES];
    const char *problem = check_header(mission, header,
                                       (long)read_at(fd, header, sizeof header, 0));
    if (problem) {
        return problem;
    }
    uint32_t claimed[2] = {0, 0};  /* sequence numbers as the slots claim them */
    for (uint32_t slot = 0; slot < 2; slot++) {
        if (read_at(fd, &claimed[slot], 4, slot_offset(slot)) != 4) {
            claimed[slot] = 0;
        }
    }
    uint32_t first = claimed[1] > claimed[0] ? 1 : 0;  /* the newer one, if it is intact */
    for (uint32_t slot = first, tries = 0; tries < 2; tries++, slot ^= 1u) {
        ssize_t n = read_at(fd, record_buf, sizeof record_buf, slot_offset(slot));
        const char *why = gp_checkpoint_decode(mission, record_buf, n < 0 ? 0 : (size_t)n,
                                               seq, rt);
        if (!why) {
            return NULL;
        }
        problem = problem ? problem : why;  /* the newer one's: a torn write, or none */
    }
    return problem;
}

int gp_checkpoint_open(gp_checkpoint *cp, const char *dir, const gp_mission *mission,
                       gp_runtime *rt, int *resumed, const char **problem)
{
    char path[GP_PATH_MAX];
    cp->fd = -1;
    cp->seq = 1;
    cp->journal_at = 0;
    *resumed = 0;
    *problem = "state directory path too long";
    if (gp_path_join(dir, "checkpoint", path) < 0) {
        return -1;
    }
    int fd = open(path, O_RDWR);
    if (fd < 0 && errno == ENOENT) {
        if (create_checkpoint(dir, mission, rt) < 0 || (fd = open(path, O_RDWR)) < 0) {
            *problem = strerror(errno);
            return -1;
        }
        cp->fd = fd;
        return 0;
    }
    if (fd < 0) {
        *problem = strerror(errno);
        return -1;
    }
    *resumed = 1;
    *problem = load_newest(fd, mission, rt, &cp->seq);
    if (*problem) {
        close(fd);
        return -1;
    }
    cp->fd = fd;
    return 0;
}

int gp_checkpoint_store(gp_checkpoint *cp, const gp_mission *mission, const gp_runtime *rt)
{
    uint32_t seq = cp->seq + 1;
    size_t len = gp_checkpoint_encode(mission, rt, seq, record_buf);
    if (write_at(cp->fd, record_buf, len, slot_offset(seq)) < 0 || fdatasync(cp->fd) < 0) {
        return -1;
    }
    cp->seq = seq;
    cp->journal_at = 0;  /* the entries before name the record before: no longer read */
    return 0;
}

/* ---- the journal ---------------------------------------------------------------------- */

/* An entry in 32-bit words, in the board's byte order: the number of the record it
 * follows, the payload's length in bytes, the payload (zeros to a whole word), and two
 * Fletcher sums over the words before them (modulo 2^32): the first changes with any
 * one damaged word, the second with two words swapped; other damage goes unnoticed once
 * in 2^32 or so, and must also keep the record number and a length that fits. */
static uint32_t entry_buf[GP_JOURNAL_MAX_ENTRY / 4];

static void fletcher_sums(const uint32_t *words, size_t n, uint32_t *sums)
{
    uint32_t a = 0, b = 0;
    for (size_t i = 0; i < n; i++) {
        a += words[i];
        b += a;
    }
    sums[0] = a;
    sums[1] = b;
}

/* Words of an entry with a payload of `len` bytes, its sums included. */
static size_t entry_words(size_t len)
{
    return 2 + (len + 3) / 4 + 2;
}

int gp_journal_append(gp_checkpoint *cp, const uint8_t *payload, size_t len)
{
    if (len > GP_MAX_PAYLOAD) {
        errno = EINVAL;
        return -1;
    }
    size_t words = entry_words(len);
    if (cp->journal_at + 4 * words > GP_JOURNAL_BYTES) {
        return 1;
    }
    entry_buf[0] = cp->seq;
    entry_buf[1] = (uint32_t)len;
    entry_buf[2 + len / 4] = 0;  /* the last payload word's padding (none: a sum's place) */
    memcpy(entry_buf + 2, payload, len);
    fletcher_sums(entry_buf, words - 2, entry_buf + words - 2);
    if (write_at(cp->fd, entry_buf, 4 * words, JOURNAL_OFFSET + cp->journal_at) < 0
        || fdatasync(cp->fd) < 0) {
        return -1;
    }
    cp->journal_at += (uint32_t)(4 * words);
    return 0;
}

long gp_journal_next(gp_checkpoint *cp, uint8_t *payload)
{
    size_t room = GP_JOURNAL_BYTES - cp->journal_at;
    ssize_t n = read_at(cp->fd, entry_buf, room < sizeof entry_buf ? room : sizeof entry_buf,
                        JOURNAL_OFFSET + cp->journal_at);
    if (n < 16 || entry_buf[0] != cp->seq || entry_buf[1] > GP_MAX_PAYLOAD
        || 4 * entry_words(entry_buf[1]) > (size_t)n) {
        return -1;
    }
    size_t len = entry_buf[1], words = entry_words(len);
    uint32_t sums[2];
    fletcher_sums(entry_buf, words - 2, sums);
    if (sums[0] != entry_buf[words - 2] || sums[1] != entry_buf[words - 1]) {
        return -1;
    }
    memcpy(payload, entry_buf + 2, len);
    cp->journal_at += (uint32_t)(4 * words);
    return (long)len;
}

void gp_checkpoint_close(gp_checkpoint *cp)
{
    if (cp->fd >= 0) {
        close(cp->fd);
        cp->fd = -1;
    }
}

int gp_path_join(const char *dir, const char *name, char *out)
{
    int n = snprintf(out, GP_PATH_MAX, "%s/%s", dir, name);
    return (n < 0 || n >= GP_PATH_MAX) ? -1 : 0;
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
    static const char *const names[] = {"none",   "start", "goto",   "call",
                                        "return", "exit",  "reserve", "envelope"};
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
    return (write_at(fd, line, (size_t)n, -1) < 0 || fsync(fd) < 0) ? -1 : 0;
}
