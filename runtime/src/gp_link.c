/* The runtime program: start-up checks, then one loop that reads the line, answers
 * each SENSORS with a COMMAND and watches for silence. All buffers are static. */
#define _POSIX_C_SOURCE 200809L
#include "gp_link.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "gp_frame.h"
#include "gp_key.h"
#include "gp_mission.h"
#include "gp_plan.h"
#include "gp_runtime.h"
#include "gp_serial.h"
#include "gp_store.h"
#include "gp_update.h"

#define READ_CHUNK 256
#define ERROR_LEN 512
#define RELEASED_WAIT_S 1.0  /* [s] the longest poll while the link is down */

typedef struct {
    const gp_mission *mission;
    const gp_args *args;
    const char *prog;
    int fd;                          /* the serial line */
    int own_pty;                     /* fd is the master of a pty we created */
    double clock_mhz;                /* last clock written to --clock-file, 0: none */
    int clock_failed;                /* --clock-file could not be written: said once */
    int suspend_failed;              /* --suspend-file could not be written: said once */
    int events_fd;                   /* events.log, -1 without a state directory */
    gp_frame_reader reader;
    uint8_t seq;                     /* our last frame's seq */
    uint8_t ack;                     /* seq of the last valid frame received */
    uint8_t last_wire[GP_MAX_FRAME]; /* our last frame, re-sent on NAK; payloads are packed
                                        into it where the frame will carry them */
    size_t last_len;
    gp_command sent;                 /* our last COMMAND ... */
    uint8_t sent_seq, has_sent;      /* ... and its frame's seq */
    gp_command acked;                /* the last COMMAND the science computer acknowledged */
    uint8_t has_acked;
    int answered;                    /* a SENSORS frame was answered ... */
    uint8_t answered_seq;            /* ... with this seq */
    double last_valid_s;             /* when the last valid frame arrived */
    int heard;                       /* a valid frame arrived since the clock was read */
    double hello_due_s;              /* next HELLO, before the first SENSORS */
    int has_plan;
    uint16_t plan_total, plan_received;
    uint16_t update_total, update_received;  /* a plan update being assembled */
    uint32_t dropped;                /* frames dropped (bad CRC, COBS, ...) */
    uint32_t stale;                  /* SENSORS of a tick older than the last answered */
    int released;                    /* the watchdog gave control to layered control */
} link_state;

static gp_runtime runtime;
static volatile sig_atomic_t stop_signal;  /* SIGTERM/SIGINT/SIGHUP received */
static int crash_fd = -1;                  /* the line, for the crash handler */
static uint8_t crash_release[GP_MAX_FRAME];  /* RELEASE (internal error), framed ahead */
static size_t crash_release_len;
static gp_plan plan;
static char plan_text[GP_MAX_PLAN_BYTES + 1];   /* a plan read or assembled, an update's result */
static char held_text[GP_MAX_PLAN_BYTES];       /* the file of the plan in force: updates */
static size_t held_len;                         /* apply to it; 0: no plan */
static uint8_t update_rx[GP_MAX_UPDATE_BYTES];  /* a plan update as it arrives */
static gp_checkpoint checkpoint = {-1, 0, 0};
static gp_plan_auth auth;                  /* with --key: what the next plan must show */
static const gp_plan_auth *plan_auth;      /* &auth with --key, else NULL */

static void say(const link_state *s, const char *message)
{
    fprintf(stderr, "%s: %s\n", s->prog, message);
}

/* The serial line: a device, or with `--device pty` a new pseudo-terminal whose peer
 * path is the first line on stdout (for a simulated science computer to open). */
static int open_line(link_state *s, char *message)
{
    char peer[128];
    int pty = strcmp(s->args->device, GP_DEVICE_PTY) == 0;
    s->fd = pty ? gp_serial_open_pty(peer, sizeof peer) : gp_serial_open(s->args->device);
    s->own_pty = pty;
    if (s->fd < 0) {
        snprintf(message, ERROR_LEN, "%.200s: cannot open the serial line: %s",
                 pty ? "a new pseudo-terminal" : s->args->device, strerror(errno));
        return -1;
    }
    if (pty) {
        printf("%s\n", peer);
        fflush(stdout);
    }
    return 0;
}

/* Where the next frame's payload is packed: framing seals it where it lies. */
static uint8_t *outgoing(link_state *s)
{
    return s->last_wire + GP_FRAME_PAYLOAD_AT;
}

/* Send the payload packed at outgoing(s) as a new frame. */
static int send_frame(link_state *s, uint8_t type, size_t len)
{
    s->seq = (uint8_t)(s->seq + 1);
    s->last_len = gp_frame_seal(s->last_wire, type, s->seq, s->ack, len);
    return gp_serial_write(s->fd, s->last_wire, s->last_len);
}

/* A NAK is not kept as the frame to re-send: NAK answered by NAK would never end. */
static void send_nak(link_state *s)
{
    uint8_t wire[GP_MAX_FRAME];
    s->dropped++;
    s->seq = (uint8_t)(s->seq + 1);
    size_t n = gp_frame_build(GP_MSG_NAK, s->seq, s->ack, NULL, 0, wire);
    gp_serial_write(s->fd, wire, n);
}

/* Give control back to the glider's own layered control: RELEASE on the line. */
static void hand_over(link_state *s, gp_release_reason reason)
{
    *outgoing(s) = (uint8_t)reason;
    send_frame(s, GP_MSG_RELEASE, 1);
    gp_serial_drain(s->fd, 1.0);  /* the RELEASE must reach the line before we go on */
}

static int send_command(link_state *s, const gp_command *command, int whole);

/* While lingering after the mission's exit: a SENSORS of the last tick again means its
 * COMMAND was lost on the line, so it goes again; a damaged frame gets its NAK. */
static void answer_late(void *ctx, uint8_t *bytes, size_t len)
{
    link_state *s = ctx;
    for (size_t i = 0, used; i < len; i += used) {
        gp_frame frame;
        uint32_t tick;
        uint8_t flags;
        int result = gp_frame_reader_feed(&s->reader, bytes + i, len - i, &used, &frame);
        if (result > 0) {
            send_nak(s);
        } else if (result == GP_FRAME_OK && frame.type == GP_MSG_SENSORS
                   && gp_sensors_unpack(&frame, s->mission->read_mask, &tick, &flags,
                                        runtime.sensors) == GP_FRAME_OK
                   && runtime.has_command && tick == runtime.last_command.tick) {
            s->ack = frame.seq;
            send_command(s, &runtime.last_command, 1);
        }
    }
}

/* Give control back for good and end with `status`. */
static int release(link_state *s, gp_release_reason reason, int status)
{
    if (s->dropped || s->stale) {
        fprintf(stderr, "%s: link: %lu damaged frames dropped, %lu stale SENSORS ignored\n",
                s->prog, (unsigned long)s->dropped, (unsigned long)s->stale);
    }
    if (!s->released || reason != GP_RELEASE_LINK_SILENT) {
        hand_over(s, reason);
    }
    if (s->own_pty) {
        gp_serial_linger(s->fd, s->args->link_timeout_s,
                         reason == GP_RELEASE_MISSION_EXITED || reason == GP_RELEASE_ENERGY_RESERVE
                             || reason == GP_RELEASE_ENVELOPE ? answer_late : NULL, s);
    }
    crash_fd = -1;
    close(s->fd);
    if (s->events_fd >= 0) {
        close(s->events_fd);
    }
    gp_checkpoint_close(&checkpoint);
    return status;
}

/* A command outside the envelope that hands control back (the fault action). */
static int envelope_releases(const link_state *s, const gp_tick_report *report)
{
    return gp_envelope_ends(&s->mission->envelope, &report->envelope)
           && s->mission->envelope.action == GP_ENVELOPE_FAULT;
}

/* A command held at the envelope's edge (the clamp action), flown on. */
static int envelope_holds(const link_state *s, const gp_tick_report *report)
{
    return report->envelope.limit != GP_LIMIT_NONE
           && !gp_envelope_ends(&s->mission->envelope, &report->envelope);
}

/* What the envelope guard did, on stderr: the state, the limit, the value and the bound. */
static void say_envelope(link_state *s, const gp_tick_report *report)
{
    char message[ERROR_LEN];
    gp_envelope_say(&s->mission->envelope, &report->envelope,
                    runtime.sensors[GP_SENSOR_MISSIONTIME],
                    s->mission->states[report->envelope_state].name, message, sizeof message);
    say(s, message);
}

/* The mission is over, by its exit or by a guard: hand over for good. */
static int end_mission(link_state *s)
{
    if (runtime.last_command.transition == GP_TR_ENVELOPE) {
        return release(s, GP_RELEASE_ENVELOPE, GP_EXIT_ENVELOPE);
    }
    if (runtime.last_command.transition == GP_TR_RESERVE) {
        say(s, "the battery reached its reserve: the mission ends, surfacing; releasing "
               "control");
        return release(s, GP_RELEASE_ENERGY_RESERVE, GP_EXIT_RESERVE);
    }
    return release(s, GP_RELEASE_MISSION_EXITED, GP_EXIT_DONE);
}

/* ---- what a tick leaves in the state directory ------------------------------- */

/* The tick's transitions (and a refused one) in the event log. */
static int log_transitions(link_state *s, const gp_tick_report *report)
{
    if (s->events_fd < 0) {
        return 0;
    }
    double time_s = runtime.sensors[GP_SENSOR_MISSIONTIME];
    for (int i = 0; i < report->n_transitions; i++) {
        const gp_transition *t = &report->transitions[i];
        if (gp_events_append(s->events_fd, s->mission, time_s, gp_transition_name(t->kind),
                             t->from, t->to, t->depth) < 0) {
            return -1;
        }
    }
    if (report->fault) {
        const gp_transition *t = &report->refused;
        gp_events_append(s->events_fd, s->mission, time_s, "fault", t->from, t->to, t->depth);
    }
    if (envelope_releases(s, report) || envelope_holds(s, report)) {
        /* a surfacing is the tick's `envelope` transition, logged above */
        gp_events_append(s->events_fd, s->mission, time_s,
                         envelope_releases(s, report) ? "fault" : "clamp", report->envelope_state,
                         report->envelope_state, runtime.machine.depth);
    }
    return 0;
}

/* The whole runtime state as a new checkpoint record, with the event log's size: lines
 * past it belong to ticks after it. */
static int store_record(link_state *s)
{
    off_t size = lseek(s->events_fd, 0, SEEK_END);
    runtime.events_log_bytes = size < 0 ? 0 : (uint32_t)size;
    return gp_checkpoint_store(&checkpoint, s->mission, &runtime);
}

/* Log the tick's transitions, and keep what a resumed runtime needs of the tick: before
 * its COMMAND goes out. A tick with a transition or a fault gets a record (it holds the
 * log's size); any other tick, only the SENSORS payload it stepped, in the checkpoint's
 * journal, from which a resumed runtime steps the tick again, to the same state: the
 * readings a later SENSORS frame may leave out (a powered-off CTD's last one) and the
 * tracker's window come back as they were. A full journal gives way to a record. */
static int persist(link_state *s, const gp_frame *frame, const gp_tick_report *report)
{
    if (report->n_transitions == 0 && !report->fault
        && report->envelope.limit == GP_LIMIT_NONE) {  /* most ticks */
        int journaled = s->args->state_dir
                            ? gp_journal_append(&checkpoint, frame->payload, frame->length)
                            : 0;
        return journaled == 1 ? store_record(s) : journaled;
    }
    if (log_transitions(s, report) < 0) {
        return -1;
    }
    return s->args->state_dir ? store_record(s) : 0;
}

static gp_run_options run_options(const link_state *s)
{
    return (gp_run_options){s->has_plan ? &plan : NULL, (uint8_t)s->args->naive_tracker};
}

/* One tick of the mission on the readings in runtime.sensors. */
static void step(link_state *s, uint32_t tick, gp_command *command, gp_tick_report *report)
{
    gp_run_options options = run_options(s);
    gp_runtime_tick(&runtime, s->mission, &options, tick, command, report);
}

/* ---- start-up ---------------------------------------------------------------- */

/* The key provisioned on the vehicle: from now on every plan must be signed with it. */
static int load_key(const char *path, char *message)
{
    if (gp_key_load(path, auth.key, message, ERROR_LEN) < 0) {
        return -1;
    }
    plan_auth = &auth;
    return 0;
}

/* A plan just accepted, whose file is `text`: with a key, the next one must be newer, and
 * an update applies to this file. */
static void adopt_plan(link_state *s, const char *text, size_t len)
{
    s->has_plan = 1;
    memcpy(held_text, text, len);
    held_len = len;
    if (plan_auth && plan.is_signed) {
        auth.last_seq = plan.seq;
        memcpy(auth.last_tag, plan.tag, sizeof auth.last_tag);
    }
}

static int load_plan(link_state *s, const char *path, char *message)
{
    long len = gp_read_file(path, plan_text, GP_MAX_PLAN_BYTES);
    if (len < 0) {
        snprintf(message, ERROR_LEN, "%.200s: cannot read the plan file%s", path,
                 len == -1 ? " (no such file)" : " (unreadable, or larger than 65536 bytes)");
        return -1;
    }
    char error[GP_PLAN_ERROR_LEN];
    if (gp_plan_read(plan_text, (size_t)len, s->mission, plan_auth, &plan, error) < 0) {
        snprintf(message, ERROR_LEN, "%.80s %.170s", path, error);
        return -1;
    }
    adopt_plan(s, plan_text, (size_t)len);
    return 0;
}

/* A plan adopted over the link outlives a restart, but only as a plan that would be
 * accepted over the link now: signed with the key and newer than --plan. Anything else
 * gives way to --plan, and the runtime says so. */
static void resume_plan(link_state *s, const char *path)
{
    char message[ERROR_LEN];
    if (access(path, F_OK) != 0) {
        return;
    }
    if (!plan_auth) {
        snprintf(message, sizeof message, "%.200s: not flown: without --key no plan from the "
                 "link is trusted", path);
        say(s, message);
        return;
    }
    uint32_t before = s->has_plan ? auth.last_seq : 0;
    if (load_plan(s, path, message) < 0) {
        char note[ERROR_LEN + 64];
        snprintf(note, sizeof note, "%.400s; flying %s", message,
                 s->has_plan ? "--plan" : "without a plan");
        say(s, note);
        return;
    }
    if (before != 0 && plan.seq != before) {
        snprintf(message, sizeof message, "%.200s: flying the plan received over the link "
                 "(seq %lu), newer than --plan (seq %lu)", path, (unsigned long)plan.seq,
                 (unsigned long)before);
        say(s, message);
    }
}

/* The ticks journaled after the checkpoint's record, stepped again as they were stepped
 * before the restart (their transitions are logged: none, unless the plan in force
 * changed). A new record then holds them, and the journal starts afresh. */
static int replay_journal(link_state *s)
{
    static uint8_t payload[GP_MAX_PAYLOAD];
    for (long len; (len = gp_journal_next(&checkpoint, payload)) >= 0;) {
        gp_frame frame = {GP_MSG_SENSORS, 0, 0, (uint16_t)len, payload};
        uint32_t tick;
        uint8_t flags;
        gp_command command;
        gp_tick_report report;
        if (gp_sensors_unpack(&frame, s->mission->read_mask, &tick, &flags, runtime.sensors)
            != GP_FRAME_OK) {
            break;
        }
        step(s, tick, &command, &report);
        if (log_transitions(s, &report) < 0) {
            return -1;
        }
    }
    return checkpoint.journal_at > 0 ? store_record(s) : 0;
}

/* The state directory: the event log, then the checkpoint. Resume from the checkpoint
 * (and its plan) if there is one; else the checkpoint comes into being holding the state
 * before the first tick, and the place in the log where this mission's lines begin. */
static int load_state(link_state *s, char *message)
{
    const char *dir = s->args->state_dir;
    char path[GP_PATH_MAX];
    if (mkdir(dir, 0755) < 0 && errno != EEXIST) {
        snprintf(message, ERROR_LEN, "%.200s: cannot create the state directory: %s", dir,
                 strerror(errno));
        return -1;
    }
    if (gp_path_join(dir, "events.log", path) < 0) {
        snprintf(message, ERROR_LEN, "state directory path too long");
        return -1;
    }
    s->events_fd = open(path, O_WRONLY | O_CREAT | O_APPEND, 0644);
    off_t size = s->events_fd < 0 ? -1 : lseek(s->events_fd, 0, SEEK_END);
    if (size < 0) {
        snprintf(message, ERROR_LEN, "%.200s: %s", path, strerror(errno));
        return -1;
    }
    runtime.events_log_bytes = (uint32_t)size;
    int resumed;
    const char *problem;
    if (gp_checkpoint_open(&checkpoint, dir, s->mission, &runtime, &resumed, &problem) < 0) {
        snprintf(message, ERROR_LEN, "%.180s/checkpoint: %s%s", dir, problem,
                 resumed ? "; remove it to start the mission afresh" : "");
        return -1;
    }
    /* Lines logged after the checkpoint belong to a tick the resumed runtime steps
     * again (the first tick too: killed between its `start` and its checkpoint): drop
     * them, so that every transition is logged exactly once. */
    if (resumed && size > (off_t)runtime.events_log_bytes
        && ftruncate(s->events_fd, (off_t)runtime.events_log_bytes) < 0) {
        snprintf(message, ERROR_LEN, "%.200s: cannot drop lines after the checkpoint: %s", path,
                 strerror(errno));
        return -1;
    }
    if (resumed && gp_path_join(dir, "plan", path) == 0) {
        resume_plan(s, path);
    }
    if (replay_journal(s) < 0) {
        snprintf(message, ERROR_LEN, "%.180s: cannot step the checkpoint's journal again: %s",
                 dir, strerror(errno));
        return -1;
    }
    return 0;
}

/* ---- one tick ---------------------------------------------------------------- */

/* A COMMAND as its changes against the last one the science computer acknowledged,
 * or whole (`whole`, or none acknowledged since the start). */
static int send_command(link_state *s, const gp_command *command, int whole)
{
    size_t len = gp_command_pack(command, whole || !s->has_acked ? NULL : &s->acked,
                                 outgoing(s));
    int result = send_frame(s, GP_MSG_COMMAND, len);
    s->sent = *command;
    s->sent_seq = s->seq;
    s->has_sent = 1;
    return result;
}

/* Write `text` to a control file of the platform (a sysfs file; in simulation a plain
 * one), opened with `flags` besides O_WRONLY. @return 0, or the errno of what failed. */
static int write_control(const char *path, int flags, const char *text, size_t len)
{
    int fd = open(path, O_WRONLY | O_CLOEXEC | flags);
    int written = fd >= 0 && write(fd, text, len) == (ssize_t)len;
    int error = written ? 0 : errno ? errno : EIO;
    if (fd >= 0) {
        close(fd);
    }
    return error;
}

/* The clock of the current state, written in kHz to --clock-file (a cpufreq
 * scaling_setspeed under the userspace governor) when it changes: the plan's, or without
 * a plan the mission's `computer clock` (none: left alone). A clock that cannot be set
 * costs energy, not safety: say so once and fly on. */
static void follow_clock(link_state *s)
{
    if (!s->args->clock_path || s->clock_failed || runtime.machine.state == GP_EXITED) {
        return;
    }
    double mhz = s->has_plan ? plan.states[runtime.machine.state].clock_mhz
                             : s->mission->states[runtime.machine.state].clock_mhz;
    if (mhz == 0 || mhz == s->clock_mhz) {
        return;
    }
    char text[32];
    int len = snprintf(text, sizeof text, "%ld\n", lround(mhz * 1000.0));
    int error = write_control(s->args->clock_path, O_TRUNC, text, (size_t)len);
    if (error) {
        char message[ERROR_LEN];
        snprintf(message, sizeof message, "%.200s: cannot set the clock to %g MHz: %s; "
                 "flying on at the present clock", s->args->clock_path, mhz, strerror(error));
        say(s, message);
        s->clock_failed = 1;
        return;
    }
    s->clock_mhz = mhz;
}

/* After answering a tick in a state that sleeps between ticks (the plan's SLEEP, or
 * without a plan the mission's `computer sleep between ticks`): "mem" to --suspend-file,
 * the platform's suspend interface (/sys/power/state). On a board the write returns when
 * the next SENSORS frame on the serial line (or the RTC) wakes it; a frame whose first
 * bytes the wake-up loses is re-sent like any damaged frame (docs/protocol.md). A board
 * that cannot sleep costs energy, not safety: say so once and stay awake. */
static void sleep_until_next_tick(link_state *s)
{
    gp_run_options options = run_options(s);
    if (!s->args->suspend_path || s->suspend_failed
        || !gp_runtime_sleeps(&runtime, s->mission, &options)) {
        return;
    }
    int error = write_control(s->args->suspend_path, O_APPEND, "mem\n", 4);
    if (error) {
        char message[ERROR_LEN];
        snprintf(message, sizeof message, "%.200s: cannot sleep between ticks: %s; staying "
                 "awake", s->args->suspend_path, strerror(error));
        say(s, message);
        s->suspend_failed = 1;
    }
}

/* @return -1 to go on, else the exit status */
static int on_sensors(link_state *s, const gp_frame *frame)
{
    uint32_t tick;
    uint8_t flags;
    /* all or nothing: a SENSORS that does not unpack changes no reading */
    if (gp_sensors_unpack(frame, s->mission->read_mask, &tick, &flags, runtime.sensors)
        != GP_FRAME_OK) {
        send_nak(s);
        return -1;
    }
    int resync = (flags & GP_SENSORS_RESYNC) != 0;
    if (resync) {  /* the science computer holds no COMMAND we could name as a base */
        s->has_acked = 0;
    } else if (s->has_sent && frame->ack == s->sent_seq) {
        s->acked = s->sent;
        s->has_acked = 1;
    }
    /* A stale SENSORS (a copy of an older tick, delayed or duplicated on the line, with a
     * seq of its own): stepping it would run mission time backwards. Not answered: the
     * science computer no longer waits for that tick. */
    if (runtime.has_command && tick < runtime.last_command.tick) {
        s->stale++;
        return -1;
    }
    /* A re-sent SENSORS (same seq), or the tick a checkpoint already answered. */
    if ((s->answered && frame->seq == s->answered_seq)
        || (runtime.has_command && tick == runtime.last_command.tick)) {
        s->answered = 1;
        s->answered_seq = frame->seq;
        send_command(s, &runtime.last_command, resync);
        return -1;
    }
    gp_command command;
    gp_tick_report report;
    step(s, tick, &command, &report);
    if (persist(s, frame, &report) < 0) {
        say(s, "cannot write the checkpoint or event log; releasing control");
        return release(s, GP_RELEASE_INTERNAL_ERROR, GP_EXIT_INTERNAL);
    }
    if (report.envelope.limit != GP_LIMIT_NONE) {
        say_envelope(s, &report);
    }
    if (envelope_releases(s, &report)) {
        return release(s, GP_RELEASE_ENVELOPE, GP_EXIT_ENVELOPE);
    }
    if (report.fault) {
        char message[ERROR_LEN];
        snprintf(message, sizeof message, "mission fault at missiontime %g s in state %.64s: %s; "
                 "releasing control", runtime.sensors[GP_SENSOR_MISSIONTIME],
                 s->mission->states[report.refused.from].name,
                 report.fault == GP_STEP_OVERFLOW ? "call overflows the state stack"
                 : report.fault == GP_STEP_UNDERFLOW ? "return with an empty stack"
                 : "event targets no state");
        say(s, message);
        return release(s, GP_RELEASE_INTERNAL_ERROR, GP_EXIT_INTERNAL);
    }
    follow_clock(s);
    s->answered = 1;
    s->answered_seq = frame->seq;
    send_command(s, &command, resync);
    if (runtime.machine.state == GP_EXITED) {
        return end_mission(s);
    }
    sleep_until_next_tick(s);
    return -1;
}

enum { WHOLE_PLAN, PLAN_UPDATE };  /* what note_plan tells of */

/* What became of a plan, or a plan update, sent over the link: on stderr, and appended
 * to the state directory's plans.log (`time_s accepted|rejected seq [update: ]message`),
 * which outlives a restart as the event log does. `seq` is the plan in force once
 * accepted, 0 if not. */
static void note_plan(link_state *s, int update, int accepted, const char *message)
{
    static const char *const said[2][2] = {{"rejected", "accepted"}, {"refused", "applied"}};
    char line[ERROR_LEN];
    unsigned long seq = accepted ? (unsigned long)plan.seq : 0;
    snprintf(line, sizeof line, "plan%s over the link %s (seq %lu): %.300s",
             update == PLAN_UPDATE ? " update" : "", said[update][accepted != 0], seq, message);
    say(s, line);
    char path[GP_PATH_MAX];
    if (!s->args->state_dir || gp_path_join(s->args->state_dir, "plans.log", path) < 0) {
        return;
    }
    int fd = open(path, O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
    if (fd < 0) {
        return;
    }
    double time_s = runtime.sensors[GP_SENSOR_MISSIONTIME];
    int n = snprintf(line, sizeof line, "%.17g %s %lu %s%.300s\n", isnan(time_s) ? 0 : time_s,
                     said[WHOLE_PLAN][accepted != 0], seq, update == PLAN_UPDATE ? "update: " : "",
                     message);
    if (n > 0 && (size_t)n < sizeof line && write(fd, line, (size_t)n) == n) {
        fsync(fd);
    }
    close(fd);
}

/* Assemble PLAN pieces sent in order from offset 0; read the plan when complete. */
static void on_plan(link_state *s, const gp_frame *frame)
{
    uint16_t offset, total, len;
    const uint8_t *data;
    if (gp_plan_piece_unpack(frame, &offset, &total, &data, &len) != GP_FRAME_OK) {
        send_nak(s);
        return;
    }
    if (offset == 0) {
        s->plan_total = total;
        s->plan_received = 0;
    }
    if (total == 0 || total != s->plan_total || offset != s->plan_received
        || (uint32_t)offset + len > total) {
        return;  /* out of order: the science computer re-sends the whole plan */
    }
    memcpy(plan_text + offset, data, len);
    s->plan_received = (uint16_t)(offset + len);
    if (s->plan_received < total) {
        return;
    }
    s->plan_received = 0;
    char error[GP_PLAN_ERROR_LEN], status[GP_MAX_PAYLOAD];
    int accepted = 0;
    if (!plan_auth) {
        snprintf(error, sizeof error, "no key is provisioned on this vehicle: plans over the "
                 "link are refused (start the runtime with --key FILE)");
    } else if (gp_plan_read(plan_text, total, s->mission, plan_auth, &plan, error) == 0) {
        accepted = 1;
        adopt_plan(s, plan_text, total);
        /* a record first: the ticks journaled so far were stepped under the plan before,
         * and a resumed runtime steps the journal under the stored plan */
        if (s->args->state_dir
            && (store_record(s) < 0
                || gp_write_atomically(s->args->state_dir, "plan", plan_text, total) < 0)) {
            say(s, "warning: cannot store the new plan in the state directory");
        }
    }
    snprintf(status, sizeof status, "%s", accepted ? "ok" : error);
    note_plan(s, WHOLE_PLAN, accepted, status);
    send_frame(s, GP_MSG_PLAN_STATUS, gp_plan_status_pack(accepted, status, outgoing(s)));
}

/* Make the update in update_rx (`len` bytes) the plan in force, or say why not. The new
 * plan's file is made where plans over the link are assembled: an update ends a plan's
 * assembly, which the science computer sends again whole. It is stored (after a record:
 * the ticks journaled so far were stepped under the plan before) before it is flown, so
 * that a power cut leaves the old plan or the new one in the state directory; a plan
 * that cannot be stored is not flown. */
static void apply_update(link_state *s, size_t len)
{
    char message[GP_UPDATE_MESSAGE_LEN];
    size_t new_len = 0;
    s->plan_received = 0;
    gp_update_status status = gp_update_apply(update_rx, len, held_len ? held_text : NULL,
                                              held_len, plan_auth, s->mission, plan_text,
                                              &new_len, &plan, message);
    if (status == GP_UPDATE_APPLIED && s->args->state_dir
        && (store_record(s) < 0
            || gp_write_atomically(s->args->state_dir, "plan", plan_text, new_len) < 0)) {
        char error[GP_PLAN_ERROR_LEN];
        int why = errno;
        gp_plan_read(held_text, held_len, s->mission, plan_auth, &plan, error);
        status = GP_UPDATE_NOT_STORED;
        snprintf(message, sizeof message, "the new plan cannot be stored in the state "
                 "directory (%.80s): plan %lu stays in force", strerror(why),
                 (unsigned long)auth.last_seq);
    } else if (status == GP_UPDATE_APPLIED) {
        adopt_plan(s, plan_text, new_len);
    }
    note_plan(s, PLAN_UPDATE, status == GP_UPDATE_APPLIED || status == GP_UPDATE_DUPLICATE,
              message);
    uint32_t seq = s->has_plan && plan_auth ? auth.last_seq : 0;
    send_frame(s, GP_MSG_UPDATE_STATUS,
               gp_update_status_pack((uint8_t)status, seq, message, outgoing(s)));
}

/* Assemble PLAN_UPDATE pieces sent in order from offset 0, as PLAN pieces; apply the
 * update when complete. One longer than an update may be is refused at its first piece. */
static void on_update(link_state *s, const gp_frame *frame)
{
    uint16_t offset, total, len;
    const uint8_t *data;
    if (gp_plan_piece_unpack(frame, &offset, &total, &data, &len) != GP_FRAME_OK) {
        send_nak(s);
        return;
    }
    if (offset == 0 && total > GP_MAX_UPDATE_BYTES) {
        char message[GP_UPDATE_MESSAGE_LEN];
        snprintf(message, sizeof message, "the update has %u bytes, more than %d",
                 (unsigned)total, GP_MAX_UPDATE_BYTES);
        note_plan(s, PLAN_UPDATE, 0, message);
        send_frame(s, GP_MSG_UPDATE_STATUS,
                   gp_update_status_pack(GP_UPDATE_MALFORMED, plan_auth ? auth.last_seq : 0,
                                         message, outgoing(s)));
        s->update_total = 0;
        return;
    }
    if (offset == 0) {
        s->update_total = total;
        s->update_received = 0;
    }
    if (total == 0 || total != s->update_total || offset != s->update_received
        || (uint32_t)offset + len > total) {
        return;  /* out of order: the science computer sends the whole update again */
    }
    memcpy(update_rx + offset, data, len);
    s->update_received = (uint16_t)(offset + len);
    if (s->update_received == total) {
        s->update_received = 0;
        apply_update(s, total);
    }
}

/* @return -1 to go on, else the exit status */
static int on_frame(link_state *s, const gp_frame *frame)
{
    s->ack = frame->seq;
    s->heard = 1;  /* the loop stamps it with the clock it reads next */
    if (s->released && frame->type == GP_MSG_SENSORS) {
        /* the link is back: take control again, from the state the mission was in; the
         * science computer may hold none of our COMMANDs, so the next goes whole */
        say(s, "link back; taking control again");
        s->released = 0;
        s->has_acked = 0;
    }
    switch (frame->type) {
    case GP_MSG_SENSORS:
        return on_sensors(s, frame);
    case GP_MSG_NAK:
        gp_serial_write(s->fd, s->last_wire, s->last_len);
        return -1;
    case GP_MSG_PLAN:
        on_plan(s, frame);
        return -1;
    case GP_MSG_PLAN_UPDATE:
        on_update(s, frame);
        return -1;
    default:  /* messages the runtime sends, not receives: ignore */
        return -1;
    }
}

static void on_stop_signal(int signal_number)
{
    stop_signal = signal_number;
}

/* An operator stopping the runtime hands the glider back instead of leaving it
 * waiting for commands that will never come. */
static void catch_stop_signals(void)
{
    struct sigaction action;
    memset(&action, 0, sizeof action);
    action.sa_handler = on_stop_signal;
    sigemptyset(&action.sa_mask);
    sigaction(SIGTERM, &action, NULL);
    sigaction(SIGINT, &action, NULL);
    sigaction(SIGHUP, &action, NULL);
}

/* A crash (a bug in the runtime or the generated mission) must not leave the glider
 * waiting for commands: the handler only calls write and _exit, both async-signal-safe. */
static void on_crash_signal(int signal_number)
{
    (void)signal_number;
    if (crash_fd >= 0) {
        ssize_t ignored = write(crash_fd, crash_release, crash_release_len);
        (void)ignored;
    }
    _exit(GP_EXIT_INTERNAL);
}

static void catch_crash_signals(link_state *s)
{
    uint8_t reason = GP_RELEASE_INTERNAL_ERROR;
    crash_release_len = gp_frame_build(GP_MSG_RELEASE, 0, 0, &reason, 1, crash_release);
    crash_fd = s->fd;
    struct sigaction action;
    memset(&action, 0, sizeof action);
    action.sa_handler = on_crash_signal;
    action.sa_flags = SA_RESETHAND;
    sigemptyset(&action.sa_mask);
    sigaction(SIGSEGV, &action, NULL);
    sigaction(SIGBUS, &action, NULL);
    sigaction(SIGFPE, &action, NULL);
    sigaction(SIGILL, &action, NULL);
    sigaction(SIGABRT, &action, NULL);
}

static int run_link(link_state *s)
{
    static uint8_t chunk[READ_CHUNK];  /* frames that lie whole in it are decoded in it */
    double retransmit_s = s->args->retransmit_ms / 1000.0;
    s->last_valid_s = gp_now_s();
    s->hello_due_s = s->last_valid_s;
    catch_stop_signals();
    catch_crash_signals(s);
    for (;;) {
        double now = gp_now_s();
        if (s->heard) {
            s->last_valid_s = now;
            s->heard = 0;
        }
        if (stop_signal) {
            say(s, "stopped by a signal; releasing control");
            return s->released ? release(s, GP_RELEASE_LINK_SILENT, GP_EXIT_LINK_LOST)
                               : release(s, GP_RELEASE_INTERNAL_ERROR, GP_EXIT_INTERNAL);
        }
        if (!s->released && now - s->last_valid_s >= s->args->link_timeout_s) {
            /* layered control flies the glider; we listen for the link to come back */
            say(s, "link silent past its timeout; releasing control");
            hand_over(s, GP_RELEASE_LINK_SILENT);
            s->released = 1;
        }
        if (!s->answered && now >= s->hello_due_s) {
            send_frame(s, GP_MSG_HELLO, gp_hello_pack(s->mission, outgoing(s)));
            s->hello_due_s = now + retransmit_s;
        }
        double wait_s = s->released ? RELEASED_WAIT_S
                                    : s->last_valid_s + s->args->link_timeout_s - now;
        if (!s->answered && s->hello_due_s - now < wait_s) {
            wait_s = s->hello_due_s - now;
        }
        /* whole milliseconds, rounded up: the poll never ends before the deadline */
        int wait_ms = wait_s > 0 ? (int)(wait_s * 1000.0) + 1 : 0;
        long n = gp_serial_read(s->fd, chunk, sizeof chunk, wait_ms);
        if (n < 0) {
            say(s, "serial read failed; releasing control");
            return release(s, GP_RELEASE_INTERNAL_ERROR, GP_EXIT_INTERNAL);
        }
        for (size_t i = 0, used; i < (size_t)n; i += used) {
            gp_frame frame;
            int result = gp_frame_reader_feed(&s->reader, chunk + i, (size_t)n - i, &used, &frame);
            if (result == GP_FRAME_OK) {
                int status = on_frame(s, &frame);
                if (status >= 0) {
                    return status;
                }
            } else if (result > 0) {
                send_nak(s);
            }
        }
    }
}

int gp_main(int argc, char **argv)
{
    static gp_args args;
    static link_state s;
    char message[ERROR_LEN];
    const char *slash = argc > 0 ? strrchr(argv[0], '/') : NULL;
    s = (link_state){.mission = &gp_mission_table, .args = &args, .fd = -1, .events_fd = -1,
                  .prog = slash ? slash + 1 : (argc > 0 ? argv[0] : "gliderplan-runtime")};
    const char *table_problem = gp_mission_check(s.mission);
    if (table_problem) {
        snprintf(message, sizeof message, "compiled mission table: %s", table_problem);
        say(&s, message);
        return GP_EXIT_INTERNAL;
    }
    gp_runtime_init(&runtime);
    if (gp_args_parse(argc, argv, &args, message, sizeof message) < 0
        || (args.key_path && load_key(args.key_path, message) < 0)
        || (args.plan_path && load_plan(&s, args.plan_path, message) < 0)
        || (args.state_dir && load_state(&s, message) < 0)) {
        say(&s, message);
        return GP_EXIT_BAD_INPUT;
    }
    if (open_line(&s, message) < 0) {
        say(&s, message);
        return GP_EXIT_BAD_INPUT;
    }
    if (runtime.started && runtime.machine.state == GP_EXITED) {
        /* restarted after the exit's checkpoint: say who we are, hand over, and answer
         * the exit's tick again if its COMMAND never reached the science computer */
        say(&s, "the checkpoint says the mission already ended");
        send_frame(&s, GP_MSG_HELLO, gp_hello_pack(s.mission, outgoing(&s)));
        return end_mission(&s);
    }
    return run_link(&s);
}
