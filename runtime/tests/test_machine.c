/* The event system against language/semantics.py: Fig. 2's trace, the state stack,
 * assignments, refused overflow and underflow.
 *
 *   Fig. 2 (fig2_mission.c):  s1 --call(500..1500)--> s2 --return(1500)--> s1
 *                             s1 --goto(2000)--> s3 --exit(2500)
 *   stacker (below):          a --call--> b --call--> a --call--> b ... depth 2 max
 */
#include <math.h>

#include "gp_machine.h"
#include "gp_test.h"

typedef struct {
    double time_s;
    uint8_t kind, from, to, depth;
} trace_row;

/* Run from start, one tick per second, collecting transitions into `rows`. */
static int run_trace(const gp_mission *mission, double until_s, trace_row *rows, int cap,
                     gp_step_result *last)
{
    gp_machine m;
    gp_transition t;
    double sensors[GP_N_SENSORS] = {0};
    int n = 0;
    gp_machine_start(&m, mission, &t);
    rows[n++] = (trace_row){0.0, t.kind, t.from, t.to, t.depth};
    *last = GP_STEP_IDLE;
    for (double time = 0; time <= until_s && m.state != GP_EXITED && n < cap; time += 1) {
        sensors[0] = time;
        sensors[1] = 10.0;
        gp_step_result r = gp_machine_step(&m, mission, sensors, &t);
        if (r == GP_STEP_TRANSITION) {
            rows[n++] = (trace_row){time, t.kind, t.from, t.to, t.depth};
        } else if (r != GP_STEP_IDLE && r != GP_STEP_ASSIGNED) {
            *last = r;
            break;
        }
    }
    return n;
}

void test_machine_should_follow_fig2(void)
{
    static const trace_row expected[] = {
        {0, GP_TR_START, GP_EXITED, 0, 0},
        {500, GP_TR_CALL, 0, 1, 1},
        {1500, GP_TR_RETURN, 1, 0, 0},
        {2000, GP_TR_GOTO, 0, 2, 0},
        {2500, GP_TR_EXIT, 2, GP_EXITED, 0},
    };
    trace_row rows[16];
    gp_step_result last;
    int n = run_trace(&gp_mission_table, 10000, rows, 16, &last);
    CHECK_INT(n, 5);
    CHECK_INT(last, GP_STEP_IDLE);
    for (int i = 0; i < 5 && i < n; i++) {
        CHECK_NEAR(rows[i].time_s, expected[i].time_s, 0);
        CHECK_INT(rows[i].kind, expected[i].kind);
        CHECK_INT(rows[i].from, expected[i].from);
        CHECK_INT(rows[i].to, expected[i].to);
        CHECK_INT(rows[i].depth, expected[i].depth);
    }
}

/* ---- a mission with variables (tests/test_semantics.py's "vars") --------------- */

static int vars_first(const double *s, const double *v) { return s[0] >= 3 && v[1] == 20; }
static void vars_assign(const double *s, double *v)
{
    v[1] = s[1] + 2;   /* bottom = depth + 2 */
    v[0] = v[1] - 10;  /* top = bottom - 10: sees the new bottom */
}
static int vars_second(const double *s, const double *v) { (void)s; return v[1] == 12; }
static const gp_event vars_events[] = {
    {vars_first, vars_assign, GP_ACT_NONE, 0},
    {vars_second, NULL, GP_ACT_EXIT, 0},
};
static const gp_profile hover_profile[] = {{GP_PROFILE_HOVER, 0, NULL, 0.0}};
static const gp_state vars_states[] = {
    {"a", {GP_ROUTE_NOHEADING, 0, 0, NULL}, hover_profile, 1, NULL, 0, vars_events, 2, 0, 0, 0, 0},
};
static const double vars_initial[] = {5, 20};
static const gp_mission vars_mission = {
    .name = "vars", .hash = "", .states = vars_states, .n_states = 1,
    .var_initial = vars_initial, .n_vars = 2, .stack_depth = 8,
};

void test_machine_should_run_assignments_in_order(void)
{
    gp_machine m;
    gp_transition t;
    double sensors[GP_N_SENSORS] = {0};
    gp_machine_start(&m, &vars_mission, &t);
    CHECK_NEAR(m.vars[0], 5, 0);
    CHECK_NEAR(m.vars[1], 20, 0);
    sensors[1] = 10.0;
    static const struct { double time; int result; double top, bottom; } rows[] = {
        {0, GP_STEP_IDLE, 5, 20},
        {3, GP_STEP_ASSIGNED, 2, 12},
        {4, GP_STEP_TRANSITION, 2, 12},
    };
    for (int i = 0; i < 3; i++) {
        sensors[0] = rows[i].time;
        CHECK_INT(gp_machine_step(&m, &vars_mission, sensors, &t), rows[i].result);
        CHECK_NEAR(m.vars[0], rows[i].top, 0);
        CHECK_NEAR(m.vars[1], rows[i].bottom, 0);
    }
    CHECK_INT(m.state, GP_EXITED);
    CHECK_INT(t.kind, GP_TR_EXIT);
    CHECK_INT(m.event_count, 2);
    CHECK_INT(gp_machine_step(&m, &vars_mission, sensors, &t), GP_STEP_IDLE);
}

/* ---- stack limits --------------------------------------------------------------- */

static int always(const double *s, const double *v) { (void)s; (void)v; return 1; }
static void count_calls(const double *s, double *v) { (void)s; v[0] += 1; }
static const gp_event call_b[] = {{always, count_calls, GP_ACT_CALL, 1}};
static const gp_event call_a[] = {{always, count_calls, GP_ACT_CALL, 0}};
static const gp_event just_return[] = {{always, NULL, GP_ACT_RETURN, 0}};
static const gp_event goto_nowhere[] = {{always, NULL, GP_ACT_GOTO, 9}};
static const double zero[] = {0};
static const gp_state stacker_states[] = {
    {"a", {GP_ROUTE_NOHEADING, 0, 0, NULL}, hover_profile, 1, NULL, 0, call_b, 1, 0, 0, 0, 0},
    {"b", {GP_ROUTE_NOHEADING, 0, 0, NULL}, hover_profile, 1, NULL, 0, call_a, 1, 0, 0, 0, 0},
};
static const gp_mission stacker = {
    .name = "stacker", .hash = "", .states = stacker_states, .n_states = 2,
    .var_initial = zero, .n_vars = 1, .stack_depth = 2,
};

void test_machine_should_refuse_a_call_past_the_stack_depth(void)
{
    trace_row rows[8];
    gp_step_result last;
    int n = run_trace(&stacker, 100, rows, 8, &last);
    CHECK_INT(n, 3);  /* start, a->b (1), b->a (2) */
    CHECK_INT(rows[2].depth, 2);
    CHECK_INT(last, GP_STEP_OVERFLOW);

    gp_machine m;
    gp_transition t;
    double sensors[GP_N_SENSORS] = {0};
    gp_machine_start(&m, &stacker, &t);
    gp_machine_step(&m, &stacker, sensors, &t);
    gp_machine_step(&m, &stacker, sensors, &t);
    CHECK_INT(gp_machine_step(&m, &stacker, sensors, &t), GP_STEP_OVERFLOW);
    /* refused: nothing changed, not even the event's assignments */
    CHECK_INT(m.state, 0);
    CHECK_INT(m.depth, 2);
    CHECK_NEAR(m.vars[0], 2, 0);
    CHECK_INT(m.event_count, 2);
    CHECK_INT(t.from, 0);
    CHECK_INT(t.to, 1);
}

void test_machine_should_refuse_return_with_an_empty_stack(void)
{
    static const gp_state states[] = {
        {"a", {GP_ROUTE_NOHEADING, 0, 0, NULL}, hover_profile, 1, NULL, 0, just_return, 1, 0, 0,
         0, 0},
    };
    static const gp_mission mission = {.name = "r", .hash = "", .states = states,
                                       .n_states = 1, .stack_depth = 1};
    gp_machine m;
    gp_transition t;
    double sensors[GP_N_SENSORS] = {0};
    gp_machine_start(&m, &mission, &t);
    CHECK_INT(gp_machine_step(&m, &mission, sensors, &t), GP_STEP_UNDERFLOW);
    CHECK_INT(m.state, 0);
    CHECK_INT(m.event_count, 0);
}

void test_machine_should_refuse_a_target_outside_the_table(void)
{
    static const gp_state states[] = {
        {"a", {GP_ROUTE_NOHEADING, 0, 0, NULL}, hover_profile, 1, NULL, 0, goto_nowhere, 1, 0, 0,
         0, 0},
    };
    static const gp_mission mission = {.name = "g", .hash = "", .states = states,
                                       .n_states = 1, .stack_depth = 1};
    gp_machine m;
    gp_transition t;
    double sensors[GP_N_SENSORS] = {0};
    gp_machine_start(&m, &mission, &t);
    CHECK_INT(gp_machine_step(&m, &mission, sensors, &t), GP_STEP_BAD_TABLE);
    CHECK_INT(m.state, 0);
}

void test_machine_goto_should_clear_the_stack(void)
{
    gp_machine m;
    gp_transition t;
    double sensors[GP_N_SENSORS] = {0};
    gp_machine_start(&m, &gp_mission_table, &t);
    sensors[0] = 600;  /* s1 calls s2 */
    CHECK_INT(gp_machine_step(&m, &gp_mission_table, sensors, &t), GP_STEP_TRANSITION);
    CHECK_INT(m.depth, 1);
    m.state = 0;       /* as if s2 had gone back to s1 without returning */
    sensors[0] = 2000;
    CHECK_INT(gp_machine_step(&m, &gp_mission_table, sensors, &t), GP_STEP_TRANSITION);
    CHECK_INT(t.kind, GP_TR_GOTO);
    CHECK_INT(m.depth, 0);
}

void test_mission_check_should_accept_fig2_and_reject_bad_tables(void)
{
    CHECK(gp_mission_check(&gp_mission_table) == NULL);
    gp_mission bad = stacker;
    bad.stack_depth = GP_MAX_STACK_DEPTH + 1;
    CHECK(gp_mission_check(&bad) != NULL);
    bad = stacker;
    bad.n_states = 0;
    CHECK(gp_mission_check(&bad) != NULL);
    static const gp_state nowhere[] = {
        {"a", {GP_ROUTE_NOHEADING, 0, 0, NULL}, hover_profile, 1, NULL, 0, goto_nowhere, 1, 0, 0,
         0, 0},
    };
    bad = stacker;
    bad.states = nowhere;
    bad.n_states = 1;
    CHECK(gp_mission_check(&bad) != NULL);  /* goto state 9 of 1 */
    bad = vars_mission;
    bad.var_initial = NULL;
    CHECK(gp_mission_check(&bad) != NULL);
    bad = gp_mission_table;
    bad.n_clocks = 0;  /* no clock a plan could name */
    CHECK(gp_mission_check(&bad) != NULL);
    bad = gp_mission_table;
    bad.max_ballast_cc = -1;  /* a pump of negative volume (0: none, a propeller AUV) */
    CHECK(gp_mission_check(&bad) != NULL);
    bad = gp_mission_table;
    bad.unplanned_speed_mps = NAN;
    CHECK(gp_mission_check(&bad) != NULL);
    static gp_state unplanned[3];  /* the alternative flown without a plan is not one */
    memcpy(unplanned, gp_mission_table.states, sizeof unplanned);
    unplanned[0].unplanned_profile = 1;
    bad = gp_mission_table;
    bad.states = unplanned;
    CHECK(gp_mission_check(&bad) != NULL);
    static gp_state unpowered[3];  /* a sensor logged but missing from the state's mask */
    memcpy(unpowered, gp_mission_table.states, sizeof unpowered);
    unpowered[1].sensor_mask &= ~(1u << GP_SENSOR_TEMP);
    bad = gp_mission_table;
    bad.states = unpowered;
    CHECK_CONTAINS(gp_mission_check(&bad), "sensor mask");
}
