/* The envelope guard: each limit, each action, and a mission whose variable takes the yo
 * past the vehicle's rating (the tick ends it, surfacing). */
#include <math.h>
#include <string.h>

#include "gp_envelope.h"
#include "gp_runtime.h"
#include "gp_test.h"

static const gp_envelope SURFACE = {
    .max_depth_m = 100.0, .max_pitch_rad = 0.9, .min_yo_band_m = 3.0, .min_inflection_s = 11.0,
    .min_speed_mps = 0.5, .max_speed_mps = 1.5, .min_thrust_w = 1.0, .max_thrust_w = 9.0,
    .max_turn_rate_rad_s = 0.15, .max_pump_power_w = 2.0,
    .pump_out_j_per_cc = 1.0, .pump_out_j_per_cc_m = 0.01, .pump_in_j_per_cc = 0.5,
    .pump_in_j_per_cc_m = -0.001, .action = GP_ENVELOPE_SURFACE};

static gp_command command(double depth_m, double pitch_rad, double ballast_cc, int climbing)
{
    gp_command cmd;
    memset(&cmd, 0, sizeof cmd);
    cmd.depth_target_m = (float)depth_m;
    cmd.pitch_rad = (float)pitch_rad;
    cmd.ballast_cc = (float)ballast_cc;
    cmd.flags = climbing ? GP_FLAG_CLIMBING : 0;
    return cmd;
}

void test_envelope_should_pass_a_command_within_the_rating(void)
{
    gp_envelope_memory memory = {0};
    gp_command cmd = command(10.0, -0.454, -233.0, 0);
    double band[2] = {5.0, 10.0};
    gp_envelope_breach b = gp_envelope_hold(&SURFACE, 233.0, &memory, 1, band, 0.0, NAN, &cmd);
    CHECK_INT(b.limit, GP_LIMIT_NONE);
    CHECK_INT(cmd.flags & GP_FLAG_ENVELOPE, 0);
    CHECK(gp_envelope_check(&SURFACE) == NULL);
}

void test_envelope_should_name_each_limit_a_command_breaks(void)
{
    double band[2] = {5.0, 10.0};
    struct { gp_command cmd; const double *band; uint8_t limit; double value; } cases[] = {
        {command(812.0, -0.454, -233.0, 0), NULL, GP_LIMIT_DEPTH, 812.0},
        {command(-1.0, 0.454, 233.0, 1), NULL, GP_LIMIT_DEPTH, -1.0},
        {command(NAN, 0.454, 233.0, 1), NULL, GP_LIMIT_DEPTH, NAN},
        {command(10.0, -1.2, -233.0, 0), band, GP_LIMIT_PITCH, -1.2},
        {command(10.0, 0.454, 560.0, 1), band, GP_LIMIT_BALLAST, 560.0},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        gp_envelope_memory memory = {0};
        gp_envelope_breach b = gp_envelope_hold(&SURFACE, 233.0, &memory, 1, cases[i].band, 0.0,
                                                NAN, &cases[i].cmd);
        CHECK_INT(b.limit, cases[i].limit);
        CHECK(fabs(b.value - cases[i].value) < 1e-6 || (isnan(b.value) && isnan(cases[i].value)));
        CHECK(gp_envelope_ends(&SURFACE, &b));
    }
    gp_envelope_memory memory = {0};
    gp_command cmd = command(10.0, -0.454, -233.0, 0);
    double deep[2] = {5.0, 3000.0}, thin[2] = {5.0, 6.0}, upside_down[2] = {5.0, -1000.0};
    CHECK_INT(gp_envelope_hold(&SURFACE, 233.0, &memory, 1, deep, 0, NAN, &cmd).limit,
              GP_LIMIT_DEPTH);
    gp_envelope_breach b = gp_envelope_hold(&SURFACE, 233.0, &memory, 1, thin, 0, NAN, &cmd);
    CHECK_INT(b.limit, GP_LIMIT_BAND);
    CHECK_NEAR(b.value, 1.0, 1e-12);
    CHECK_NEAR(b.bound, 3.0, 1e-12);
    CHECK_INT(gp_envelope_hold(&SURFACE, 233.0, &memory, 1, upside_down, 0, NAN, &cmd).limit,
              GP_LIMIT_DEPTH);
}

void test_envelope_should_stop_a_yo_turning_faster_than_its_pump(void)
{
    gp_envelope_memory memory = {0};
    double band[2] = {5.0, 10.0};
    gp_command dive = command(10.0, -0.454, -233.0, 0), climb = command(5.0, 0.454, 233.0, 1);
    CHECK_INT(gp_envelope_hold(&SURFACE, 233.0, &memory, 1, band, 0.0, NAN, &dive).limit, 0);
    CHECK_INT(gp_envelope_hold(&SURFACE, 233.0, &memory, 0, band, 4.0, NAN, &climb).limit, 0);
    dive = command(10.0, -0.454, -233.0, 0);
    CHECK_INT(gp_envelope_hold(&SURFACE, 233.0, &memory, 0, band, 40.0, NAN, &dive).limit, 0);
    climb = command(5.0, 0.454, 233.0, 1);
    gp_envelope_breach b = gp_envelope_hold(&SURFACE, 233.0, &memory, 0, band, 44.0, NAN, &climb);
    CHECK_INT(b.limit, GP_LIMIT_INFLECTION);
    CHECK_NEAR(b.value, 4.0, 1e-12);
    /* a new profile turns afresh: its first turn is never too soon */
    dive = command(10.0, -0.454, -233.0, 0);
    CHECK_INT(gp_envelope_hold(&SURFACE, 233.0, &memory, 1, band, 45.0, NAN, &dive).limit, 0);
    climb = command(5.0, 0.454, 233.0, 1);
    CHECK_INT(gp_envelope_hold(&SURFACE, 233.0, &memory, 0, band, 46.0, NAN, &climb).limit, 0);
}

void test_envelope_clamp_should_hold_values_at_the_edge_and_end_on_rates(void)
{
    gp_envelope clamp = SURFACE;
    clamp.action = GP_ENVELOPE_CLAMP;
    gp_envelope_memory memory = {0};
    gp_command cmd = command(812.0, -1.2, -560.0, 0);
    gp_envelope_breach b = gp_envelope_hold(&clamp, 233.0, &memory, 1, NULL, 0.0, NAN, &cmd);
    CHECK_INT(b.limit, GP_LIMIT_DEPTH);
    CHECK(!gp_envelope_ends(&clamp, &b));
    CHECK_NEAR(cmd.depth_target_m, 100.0, 0);
    CHECK_NEAR(cmd.pitch_rad, -(float)0.9, 0);
    CHECK_NEAR(cmd.ballast_cc, -233.0, 0);
    CHECK(cmd.flags & GP_FLAG_ENVELOPE);
    CHECK(memory.held);
    cmd = command(NAN, 0.454, 233.0, 1);
    b = gp_envelope_hold(&clamp, 233.0, &memory, 1, NULL, 0.0, NAN, &cmd);
    CHECK(gp_envelope_ends(&clamp, &b));  /* a NaN has no edge */
    double thin[2] = {5.0, 5.5};
    cmd = command(5.5, -0.454, -233.0, 0);
    b = gp_envelope_hold(&clamp, 233.0, &memory, 1, thin, 0.0, NAN, &cmd);
    CHECK_INT(b.limit, GP_LIMIT_BAND);
    CHECK(gp_envelope_ends(&clamp, &b));
}

static gp_command propelled(double speed_mps, double thrust_w)
{
    gp_command cmd = command(10.0, 0.0, 0.0, 0);
    cmd.speed_mps = (float)speed_mps;
    cmd.thrust_w = (float)thrust_w;
    return cmd;
}

void test_envelope_should_hold_speed_and_thrust_to_the_propulsion_s_range(void)
{
    struct { double speed, thrust; uint8_t limit; double bound; float held; } cases[] = {
        {0.0, 0.0, GP_LIMIT_NONE, 0.0, 0.0f},     /* the motor off */
        {1.5, 9.0, GP_LIMIT_NONE, 0.0, 1.5f},     /* the top of both ranges */
        {2.5, 0.0, GP_LIMIT_SPEED, 1.5, 1.5f},    /* above the table's top */
        {0.2, 0.0, GP_LIMIT_SPEED, 0.5, 0.5f},    /* below the slowest it runs */
        {-1.0, 0.0, GP_LIMIT_SPEED, 0.5, 0.0f},   /* astern: held off */
        {1.0, 20.0, GP_LIMIT_THRUST, 9.0, 9.0f},  /* the thruster past its command range */
        {NAN, 0.0, GP_LIMIT_SPEED, 0.5, 0.0f},    /* no side: never held */
    };
    gp_envelope clamp = SURFACE;
    clamp.action = GP_ENVELOPE_CLAMP;
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        gp_envelope_memory memory = {0};
        gp_command cmd = propelled(cases[i].speed, cases[i].thrust);
        gp_envelope_breach b = gp_envelope_hold(&SURFACE, 233.0, &memory, 1, NULL, 0.0, NAN, &cmd);
        CHECK_INT(b.limit, cases[i].limit);
        CHECK_INT(gp_envelope_ends(&SURFACE, &b), cases[i].limit != GP_LIMIT_NONE);
        if (cases[i].limit != GP_LIMIT_NONE) {
            CHECK_NEAR(b.bound, cases[i].bound, 0);
        }
        memory = (gp_envelope_memory){0};
        cmd = propelled(cases[i].speed, cases[i].thrust);
        b = gp_envelope_hold(&clamp, 233.0, &memory, 1, NULL, 0.0, NAN, &cmd);
        if (cases[i].limit == GP_LIMIT_SPEED && !isnan(cases[i].speed)) {
            CHECK(!gp_envelope_ends(&clamp, &b));
            CHECK_NEAR(cmd.speed_mps, cases[i].held, 0);
            CHECK(cmd.flags & GP_FLAG_ENVELOPE);
        } else if (cases[i].limit == GP_LIMIT_THRUST) {
            CHECK_NEAR(cmd.thrust_w, cases[i].held, 0);
        }
    }
    gp_envelope glider = SURFACE;  /* no propulsion: any speed at all is out of range */
    glider.min_speed_mps = glider.max_speed_mps = 0.0;
    gp_envelope_memory memory = {0};
    gp_command cmd = propelled(0.3, 0.0);
    CHECK_INT(gp_envelope_hold(&glider, 233.0, &memory, 1, NULL, 0.0, NAN, &cmd).limit,
              GP_LIMIT_SPEED);
}

static gp_command headed(double heading_rad)
{
    gp_command cmd = command(10.0, -0.454, -233.0, 0);
    cmd.heading_rad = (float)heading_rad;
    cmd.flags |= GP_FLAG_HEADING;
    return cmd;
}

void test_envelope_should_turn_a_heading_no_faster_than_the_vehicle(void)
{
    static const uint8_t actions[] = {GP_ENVELOPE_FAULT, GP_ENVELOPE_SURFACE, GP_ENVELOPE_CLAMP};
    for (size_t a = 0; a < sizeof actions; a++) {  /* a turn is flown under every action */
        gp_envelope envelope = SURFACE;
        envelope.action = actions[a];
        gp_envelope_memory memory = {0};
        gp_command cmd = headed(1.0);  /* the first heading: taken as it is */
        CHECK_INT(gp_envelope_hold(&envelope, 233.0, &memory, 1, NULL, 0.0, NAN, &cmd).limit, 0);
        CHECK_NEAR(cmd.heading_rad, 1.0f, 0);
        cmd = headed(1.5);  /* steering within 0.15 rad/s x 4 s: untouched */
        gp_envelope_hold(&envelope, 233.0, &memory, 0, NULL, 4.0, NAN, &cmd);
        CHECK_NEAR(cmd.heading_rad, 1.5f, 0);
        for (int tick = 3; tick < 8; tick++) {  /* a waypoint behind: 0.6 rad a tick */
            cmd = headed(4.5);
            gp_envelope_breach b = gp_envelope_hold(&envelope, 233.0, &memory, 0, NULL,
                                                    4.0 * (tick - 1), NAN, &cmd);
            CHECK_INT(b.limit, GP_LIMIT_NONE);
            CHECK_INT(cmd.flags & GP_FLAG_ENVELOPE, 0);
            CHECK_NEAR(cmd.heading_rad, fmin(1.5 + 0.6 * (tick - 2), 4.5), 1e-6);
        }
        /* across north, the short way: from 0.2 rad to 6.0 rad turns left through 0 */
        memory = (gp_envelope_memory){0};
        cmd = headed(0.2);
        gp_envelope_hold(&envelope, 233.0, &memory, 1, NULL, 0.0, NAN, &cmd);
        cmd = headed(6.0);
        gp_envelope_hold(&envelope, 233.0, &memory, 0, NULL, 1.0, NAN, &cmd);
        CHECK_NEAR(cmd.heading_rad, 0.05f, 1e-6);
        cmd = headed(6.0);
        gp_envelope_hold(&envelope, 233.0, &memory, 0, NULL, 2.0, NAN, &cmd);
        CHECK_NEAR(cmd.heading_rad, 0.2 - 0.3 + 2.0 * 3.14159265358979323846, 1e-5);
        /* no heading (noheading, no fix) forgets the last one */
        cmd = command(10.0, -0.454, -233.0, 0);
        gp_envelope_hold(&envelope, 233.0, &memory, 0, NULL, 3.0, NAN, &cmd);
        CHECK_INT(memory.headed, 0);
        cmd = headed(3.0);
        gp_envelope_hold(&envelope, 233.0, &memory, 0, NULL, 4.0, NAN, &cmd);
        CHECK_NEAR(cmd.heading_rad, 3.0f, 0);
    }
}

void test_envelope_should_stop_a_pump_working_past_its_energy_per_hour(void)
{
    /* 2 W: 7200 J an hour. A turn at 40 m moves 466 cc out at 1.4 J/cc (652.4 J), one at
     * the top 466 cc in at 0.5 J/cc (233 J): turning every 20 s pays back 40 J a leg */
    gp_envelope_memory memory = {0};
    double band[2] = {5.0, 40.0};
    double t = 0.0;
    int climbing = 0, ticks = 0;
    gp_envelope_breach b = {0};
    gp_command cmd = command(40.0, -0.454, -233.0, 0);
    gp_envelope_hold(&SURFACE, 233.0, &memory, 1, band, t, 40.0, &cmd);
    while (b.limit == GP_LIMIT_NONE && ticks < 100) {
        t += 20.0;
        climbing = !climbing;
        cmd = command(climbing ? 5.0 : 40.0, climbing ? 0.454 : -0.454,
                      climbing ? 233.0 : -233.0, climbing);
        b = gp_envelope_hold(&SURFACE, 233.0, &memory, 0, band, t, climbing ? 40.0 : 5.0, &cmd);
        ticks++;
    }
    CHECK_INT(b.limit, GP_LIMIT_PUMP_ENERGY);
    CHECK_NEAR(b.bound, 7200.0, 0);
    CHECK(b.value > 7200.0);
    CHECK_INT(ticks, 18);  /* 9 pairs of turns: 9 x (652.4 + 233 - 80) - ... > 7200 J */
    /* the clamp action cannot hold energy spent: it ends the flight */
    gp_envelope clamp = SURFACE;
    clamp.action = GP_ENVELOPE_CLAMP;
    CHECK(gp_envelope_ends(&clamp, &b));
    /* the same turns an hour apart are paid back: no breach */
    memory = (gp_envelope_memory){0};
    for (int i = 0; i < 40; i++) {
        climbing = i % 2;
        cmd = command(5.0, 0.454, climbing ? 233.0 : -233.0, climbing);
        CHECK_INT(gp_envelope_hold(&SURFACE, 233.0, &memory, 1, NULL, 600.0 * i, 40.0, &cmd).limit,
                  GP_LIMIT_NONE);
    }
}

void test_envelope_check_should_refuse_no_envelope(void)
{
    gp_envelope bad[12];
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        bad[i] = SURFACE;
    }
    bad[0].max_depth_m = 0.0;
    bad[1].max_pitch_rad = 1.6;
    bad[2].min_yo_band_m = 100.0;
    bad[3].min_inflection_s = NAN;
    bad[4].action = 3;
    bad[5].max_speed_mps = 0.1;          /* below its minimum */
    bad[6].min_thrust_w = -1.0;
    bad[7].max_speed_mps = INFINITY;     /* a range is finite */
    bad[8].max_turn_rate_rad_s = 0.0;
    bad[9].max_pump_power_w = NAN;
    bad[10].pump_in_j_per_cc_m = NAN;
    bad[11].pump_out_j_per_cc = INFINITY;
    CHECK(gp_envelope_check(&SURFACE) == NULL);
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        CHECK(gp_envelope_check(&bad[i]) != NULL);
    }
    gp_mission table = gp_mission_table;
    table.envelope.max_depth_m = NAN;
    CHECK(gp_mission_check(&table) != NULL);
}

/* A yo whose bottom is a variable an event sets past the rating (`set bottom = 3000`). */
static int at_100_s(const double *s, const double *v) { (void)v; return s[0] >= 100.0; }
static int never(const double *s, const double *v) { (void)s; (void)v; return 0; }
static void set_bottom(const double *s, double *v) { (void)s; v[0] = 3000.0; }
static void yo_to_bottom(const double *s, const double *v, double *a)
{
    (void)s;
    a[0] = 5.0; a[1] = v[0]; a[2] = .454; a[3] = .454;
}
static const gp_profile deep_profiles[] = {{GP_PROFILE_YO, 4, yo_to_bottom, 0.0}};
static const uint8_t deep_sensors[] = {GP_SENSOR_MISSIONTIME, GP_SENSOR_DEPTH};
static const gp_event deep_events[] = {{at_100_s, set_bottom, GP_ACT_NONE, 0},
                                       {never, NULL, GP_ACT_EXIT, 0}};
static const gp_state deep_states[] = {
    {"deep", {GP_ROUTE_NOHEADING, 0, 0.0, NULL}, deep_profiles, 1, deep_sensors, 2, deep_events,
     2, 0, 0, 0x3, 0},
};
static const double deep_initial[] = {10.0};

/* The test mission's envelope and limits with the one state `states` and its variable
 * `bottom` at 10 m. */
static gp_mission one_state_mission(const gp_state *states)
{
    gp_mission mission = gp_mission_table;
    mission.states = states;
    mission.n_states = 1;
    mission.var_initial = deep_initial;
    mission.n_vars = 1;
    return mission;
}

/* A runtime before its first tick with all the energy it could want. */
static void start_runtime(gp_runtime *rt)
{
    gp_runtime_init(rt);
    rt->sensors[GP_SENSOR_ENERGY_LEFT] = 1e9;
}

void test_runtime_should_surface_when_a_variable_takes_the_yo_past_the_rating(void)
{
    gp_mission mission = one_state_mission(deep_states);
    CHECK(gp_mission_check(&mission) == NULL);
    static gp_runtime rt;
    start_runtime(&rt);
    gp_run_options options = {NULL, 0};
    gp_command cmd;
    gp_tick_report report;
    uint32_t tick = 0;
    for (; tick < 100 && (!rt.started || rt.machine.state != GP_EXITED); tick++) {
        rt.sensors[GP_SENSOR_MISSIONTIME] = tick * 4.0;
        rt.sensors[GP_SENSOR_DEPTH] = 7.0;
        gp_runtime_tick(&rt, &mission, &options, tick, &cmd, &report);
    }
    CHECK_INT(tick, 26);  /* the tick at 100 s sets the bottom and ends there */
    CHECK_INT(report.envelope.limit, GP_LIMIT_DEPTH);
    CHECK_NEAR(report.envelope.value, 3000.0, 0);
    CHECK_INT(cmd.transition, GP_TR_ENVELOPE);
    CHECK_INT(cmd.state, GP_NO_STATE);
    CHECK_INT(cmd.flags, GP_FLAG_DONE | GP_FLAG_SURFACE | GP_FLAG_CLIMBING);
    CHECK_NEAR(cmd.ballast_cc, mission.max_ballast_cc, 0);
}

void test_envelope_should_say_what_it_did_in_the_simulator_s_words(void)
{
    char text[256];
    gp_envelope_breach deep = {GP_LIMIT_DEPTH, 3000.0, 100.0};
    gp_envelope_say(&SURFACE, &deep, 300.0, "s1", text, sizeof text);
    CHECK(strcmp(text, "envelope: missiontime 300 s, state s1: depth 3000 m beyond the "
                       "vehicle's 100 m; the mission ends, surfacing") == 0);
    gp_envelope clamp = SURFACE;
    clamp.action = GP_ENVELOPE_CLAMP;
    gp_envelope_say(&clamp, &deep, 8.5, "s2", text, sizeof text);
    CHECK_CONTAINS(text, "state s2: depth 3000 m beyond the vehicle's 100 m; held at the limit");
    gp_envelope fault = SURFACE;
    fault.action = GP_ENVELOPE_FAULT;
    gp_envelope_breach nan_band = {GP_LIMIT_DEPTH, -NAN, 100.0};  /* x86's negative NaN */
    gp_envelope_say(&fault, &nan_band, 18.5, "g0", text, sizeof text);
    CHECK_CONTAINS(text, "depth nan m beyond the vehicle's 100 m; releasing control");
}

/* Tick 0 holds the start, an event's goto and the envelope's end: three transitions, the
 * report holds them all (it held two: the third ran over its fault field). */
static int always(const double *s, const double *v) { (void)s; (void)v; return 1; }
static const gp_event at_once_events[] = {{always, set_bottom, GP_ACT_GOTO, 0}};
static const gp_state at_once_states[] = {
    {"deep", {GP_ROUTE_NOHEADING, 0, 0.0, NULL}, deep_profiles, 1, deep_sensors, 2,
     at_once_events, 1, 0, 0, 0x3, 0},
};

void test_runtime_should_report_start_event_and_envelope_on_one_tick(void)
{
    gp_mission mission = one_state_mission(at_once_states);
    CHECK(gp_mission_check(&mission) == NULL);
    static gp_runtime rt;
    start_runtime(&rt);
    rt.sensors[GP_SENSOR_DEPTH] = 7.0;
    gp_run_options options = {NULL, 0};
    gp_command cmd;
    gp_tick_report report;
    gp_runtime_tick(&rt, &mission, &options, 0, &cmd, &report);
    CHECK_INT(report.fault, 0);
    CHECK_INT(report.n_transitions, 3);
    CHECK_INT(report.transitions[0].kind, GP_TR_START);
    CHECK_INT(report.transitions[1].kind, GP_TR_GOTO);
    CHECK_INT(report.transitions[2].kind, GP_TR_ENVELOPE);
    CHECK_INT(cmd.transition, GP_TR_ENVELOPE);
    CHECK_INT(cmd.state, GP_NO_STATE);
}
