/* One tick end to end (no I/O): Fig. 2's trace with the COMMAND of each transition,
 * a plan's schedule in the commands, resume from a checkpoint, two transitions on
 * tick 0, a refused call. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "gp_crc.h"
#include "gp_runtime.h"
#include "gp_store.h"
#include "gp_test.h"

typedef struct {
    uint32_t tick;
    double time_s;
    uint8_t kind, from, to, depth;
} row;

/* Ticks of 10 s from `first_tick`; appends transitions to rows; stops on exit. */
static int run(gp_runtime *rt, const gp_run_options *options, uint32_t first_tick,
               uint32_t last_tick, row *rows, int n, gp_command *commands)
{
    for (uint32_t tick = first_tick; tick <= last_tick; tick++) {
        gp_command cmd;
        gp_tick_report report;
        rt->sensors[0] = tick * 10.0;
        rt->sensors[1] = 5.0 + (tick % 20);
        rt->sensors[6] = 3910.0;
        rt->sensors[7] = -7349.0;
        rt->sensors[9] = 15.0;
        gp_runtime_tick(rt, &gp_mission_table, options, tick, &cmd, &report);
        if (commands) {
            commands[tick] = cmd;
        }
        for (int i = 0; i < report.n_transitions; i++) {
            const gp_transition *t = &report.transitions[i];
            rows[n++] = (row){tick, rt->sensors[0], t->kind, t->from, t->to, t->depth};
        }
        if (rt->started && rt->machine.state == GP_EXITED) {
            break;
        }
    }
    return n;
}

static const row fig2_trace[] = {
    {0, 0, GP_TR_START, GP_EXITED, 0, 0},
    {50, 500, GP_TR_CALL, 0, 1, 1},
    {150, 1500, GP_TR_RETURN, 1, 0, 0},
    {200, 2000, GP_TR_GOTO, 0, 2, 0},
    {250, 2500, GP_TR_EXIT, 2, GP_EXITED, 0},
};

static void check_trace(const row *rows, int n)
{
    CHECK_INT(n, 5);
    for (int i = 0; i < 5 && i < n; i++) {
        CHECK_INT(rows[i].tick, fig2_trace[i].tick);
        CHECK_NEAR(rows[i].time_s, fig2_trace[i].time_s, 0);
        CHECK_INT(rows[i].kind, fig2_trace[i].kind);
        CHECK_INT(rows[i].from, fig2_trace[i].from);
        CHECK_INT(rows[i].to, fig2_trace[i].to);
        CHECK_INT(rows[i].depth, fig2_trace[i].depth);
    }
}

static gp_command commands[400];

void test_runtime_should_fly_fig2_and_report_each_transition(void)
{
    static gp_runtime rt;
    row rows[16];
    gp_run_options options = {NULL, 0};
    gp_runtime_init(&rt);
    check_trace(rows, run(&rt, &options, 0, 399, rows, 0, commands));
    static const struct {
        uint32_t tick;
        uint8_t state, depth, transition, from, to, flags;
        uint32_t power;
    } expected[] = {
        {0, 0, 0, GP_TR_START, GP_NO_STATE, 0, GP_FLAG_HEADING, 0x7},
        {1, 0, 0, GP_TR_NONE, GP_NO_STATE, GP_NO_STATE, GP_FLAG_HEADING, 0x7},
        {50, 1, 1, GP_TR_CALL, 0, 1, 0, 0x207},   /* s2: noheading, logs temp */
        {150, 0, 0, GP_TR_RETURN, 1, 0, GP_FLAG_HEADING, 0x7},
        {250, GP_NO_STATE, 0, GP_TR_EXIT, 2, GP_NO_STATE, GP_FLAG_DONE, 0},
    };
    for (unsigned i = 0; i < sizeof expected / sizeof expected[0]; i++) {
        const gp_command *c = &commands[expected[i].tick];
        CHECK_INT(c->tick, expected[i].tick);
        CHECK_INT(c->state, expected[i].state);
        CHECK_INT(c->stack_depth, expected[i].depth);
        CHECK_INT(c->transition, expected[i].transition);
        CHECK_INT(c->from, expected[i].from);
        CHECK_INT(c->to, expected[i].to);
        CHECK_INT(c->flags & (GP_FLAG_HEADING | GP_FLAG_DONE), expected[i].flags);
        CHECK_INT(c->sensor_power, expected[i].power);
    }
    CHECK_INT(commands[250].event_count, 4);
    /* s1 dives first (depth 5 < max 10) with the default ballast */
    CHECK_NEAR(commands[0].depth_target_m, 10, 0);
    CHECK_NEAR(commands[0].ballast_cc, -230, 0);
    CHECK_NEAR(commands[0].pitch_rad, -0.454, 1e-6);
}

void test_runtime_should_follow_the_plan_schedule(void)
{
    static const char body[] =
        "GPPLAN 3\nmission sampleMission\n"
        "hash 5db9c7f6bccd8ec471713fb8071fb0f3aceb0069b185b69571c5783b1814d1b9\n"
        "computer ts7800 300\nbudget_j 180000\npredicted_j 6025\ncomponents hotel\n"
        "assumptions 0\nstates 3\n"
        "state s1 300 600 0 1\npredict 1000 2 20\nenergy 2410\nprofile 0 1 0.3 150 0.31\nend\n"
        "state s2 300 600 1 1\npredict 1000 1 12\nenergy 2410\nsensor temp 60 20\n"
        "profile 0 1 0.4 200 0.3\nend\n"
        "state s3 300 600 0 1\npredict 500 1 5\nenergy 1205\nprofile 0 1 0.454 230 0.31\nend\n";
    static char text[1024];
    static gp_plan plan;
    static gp_runtime rt;
    char error[GP_PLAN_ERROR_LEN];
    size_t len = strlen(body);
    memcpy(text, body, len);
    len += (size_t)sprintf(text + len, "crc32 %08x\n",
                           (unsigned)gp_crc32(0, (const uint8_t *)body, len));
    CHECK_INT(gp_plan_read(text, len, &gp_mission_table, NULL, &plan, error), 0);
    row rows[16];
    gp_run_options options = {&plan, 0};
    gp_runtime_init(&rt);
    check_trace(rows, run(&rt, &options, 0, 399, rows, 0, commands));
    CHECK_NEAR(fabs(commands[0].pitch_rad), 0.3, 1e-6);   /* planned pitch and ballast in s1 */
    CHECK_NEAR(fabs(commands[0].ballast_cc), 150, 0);
    /* s2 entered at 500 s: temp on for the first 20 s of every 60 s */
    static const struct { uint32_t tick; int temp_on; } windows[] = {
        {50, 1}, {51, 1}, {52, 0}, {55, 0}, {56, 1}, {57, 1}, {58, 0},
    };
    for (unsigned i = 0; i < sizeof windows / sizeof windows[0]; i++) {
        CHECK_INT((commands[windows[i].tick].sensor_power >> 9) & 1u, windows[i].temp_on);
        CHECK_INT(commands[windows[i].tick].sensor_power & 0x7u, 0x7u);
    }
    CHECK_NEAR(fabs(commands[60].pitch_rad), 0.4, 1e-6);
}

void test_runtime_should_resume_from_a_checkpoint_with_the_same_trace(void)
{
    static gp_runtime rt, resumed;
    static uint8_t record[GP_CHECKPOINT_MAX_RECORD];
    gp_run_options options = {NULL, 0};
    row rows[16];
    gp_runtime_init(&rt);
    int n = run(&rt, &options, 0, 50, rows, 0, NULL);  /* up to the call into s2 */
    size_t len = gp_checkpoint_encode(&gp_mission_table, &rt, 2, record);
    run(&rt, &options, 51, 120, rows, n, NULL);        /* then it "crashes" at tick 120 */
    uint32_t seq;
    CHECK(gp_checkpoint_decode(&gp_mission_table, record, len, &seq, &resumed) == NULL);
    CHECK_INT(resumed.machine.state, 1);
    CHECK_NEAR(resumed.entry_time_s, 500, 0);
    n = run(&resumed, &options, 121, 399, rows, n, NULL);
    check_trace(rows, n);
}

static int always(const double *s, const double *v) { (void)s; (void)v; return 1; }
static const gp_event call_b[] = {{always, NULL, GP_ACT_CALL, 1}};
static const gp_event call_a[] = {{always, NULL, GP_ACT_CALL, 0}};
static const gp_profile hover[] = {{GP_PROFILE_HOVER, 0, NULL, 0.0}};
static const gp_state stacker_states[] = {
    {"a", {GP_ROUTE_NOHEADING, 0, 0, NULL}, hover, 1, NULL, 0, call_b, 1, 0, 0, 0, 0},
    {"b", {GP_ROUTE_NOHEADING, 0, 0, NULL}, hover, 1, NULL, 0, call_a, 1, 0, 0, 0, 0},
};
static const gp_mission stacker = {.name = "stacker", .hash = "", .states = stacker_states,
                                   .n_states = 2, .stack_depth = 1};

void test_runtime_should_report_start_and_event_on_tick_0_and_refuse_overflow(void)
{
    static gp_runtime rt;
    gp_run_options options = {NULL, 0};
    gp_command cmd;
    gp_tick_report report;
    gp_runtime_init(&rt);
    rt.sensors[0] = 0;
    gp_runtime_tick(&rt, &stacker, &options, 0, &cmd, &report);
    CHECK_INT(report.n_transitions, 2);
    CHECK_INT(report.transitions[0].kind, GP_TR_START);
    CHECK_INT(report.transitions[1].kind, GP_TR_CALL);
    CHECK_INT(cmd.transition, GP_TR_CALL);  /* the COMMAND carries the event's */
    CHECK_INT(cmd.state, 1);
    rt.sensors[0] = 1;
    gp_runtime_tick(&rt, &stacker, &options, 1, &cmd, &report);
    CHECK_INT(report.fault, GP_STEP_OVERFLOW);
    CHECK_INT(report.n_transitions, 0);
    CHECK_INT(cmd.state, 1);
    CHECK_INT(cmd.stack_depth, 1);
}

void test_energy_guard_should_end_the_mission_in_any_state_and_stack_depth(void)
{
    /* In s2, called from s1 (stack depth 1), the battery reaches its reserve: the mission
     * ends on that tick whatever the events say, the stack emptied, and the COMMAND says
     * surface and hold; later ticks change nothing. */
    gp_runtime rt;
    row rows[8];
    gp_command commands[80], cmd;
    gp_tick_report report;
    gp_run_options options = {NULL, 0};
    gp_runtime_init(&rt);
    rt.sensors[GP_SENSOR_ENERGY_LEFT] = 5e6;
    int n = run(&rt, &options, 0, 60, rows, 0, commands);
    CHECK_INT(n, 2);  /* start, call into s2 */
    CHECK_INT(rt.machine.depth, 1);
    rt.sensors[GP_SENSOR_ENERGY_LEFT] = 1.17e6;  /* at the reserve: the guard fires */
    n = run(&rt, &options, 61, 61, rows, n, commands);
    CHECK_INT(n, 3);
    CHECK_INT(rows[2].kind, GP_TR_RESERVE);
    CHECK_INT(rows[2].from, 1);
    CHECK_INT(rows[2].to, GP_EXITED);
    CHECK_INT(rows[2].depth, 0);
    cmd = commands[61];
    CHECK_INT(cmd.state, GP_EXITED);
    CHECK_INT(cmd.transition, GP_TR_RESERVE);
    CHECK_INT(cmd.flags, GP_FLAG_DONE | GP_FLAG_SURFACE | GP_FLAG_CLIMBING);
    CHECK_NEAR(cmd.pitch_rad, GP_SURFACE_PITCH_RAD, 1e-6);
    CHECK_NEAR(cmd.ballast_cc, 233.0, 0);
    CHECK_INT(cmd.sensor_power, 0);
    CHECK_INT(rt.machine.depth, 0);
    rt.sensors[GP_SENSOR_ENERGY_LEFT] = 5e6;  /* a reading that rose again changes nothing */
    gp_runtime_tick(&rt, &gp_mission_table, &options, 62, &cmd, &report);
    CHECK_INT(report.n_transitions, 0);
    CHECK_INT(cmd.state, GP_EXITED);

    /* no reading (NaN: a science computer that does not send it): no guard */
    gp_runtime_init(&rt);
    CHECK_INT(run(&rt, &options, 0, 400, rows, 0, NULL), 5);
}
