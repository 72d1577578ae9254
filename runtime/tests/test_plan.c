/* The strict plan reader (docs/plan-format.md) on Fig. 2 and the schedule a plan sets.
 * Each bad plan is the good one with one change; the reader must name the line. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "gp_crc.h"
#include "gp_plan.h"
#include "fig2_plan.h"
#include "gp_test.h"

static char text[GP_MAX_PLAN_BYTES + 512];

/* `body` with its crc32 line appended, into `text`; @return length. */
static size_t with_crc(const char *body)
{
    size_t len = strlen(body);
    memcpy(text, body, len);
    uint32_t crc = gp_crc32(0, (const uint8_t *)body, len);
    return len + (size_t)sprintf(text + len, "crc32 %08x\n", (unsigned)crc);
}

/* The good body with the first `from` replaced by `to`, checksummed. */
static size_t variant(const char *from, const char *to)
{
    static char body[GP_MAX_PLAN_BYTES];
    const char *at = strstr(GOOD_BODY, from);
    if (at == NULL) {
        gp_test_fail(__FILE__, __LINE__, from);
        return with_crc(GOOD_BODY);
    }
    size_t head = (size_t)(at - GOOD_BODY);
    snprintf(body, sizeof body, "%.*s%s%s", (int)head, GOOD_BODY, to, at + strlen(from));
    return with_crc(body);
}

static int read_text(size_t len, char *error)
{
    static gp_plan plan;
    return gp_plan_read(text, len, &gp_mission_table, NULL, &plan, error);
}

void test_plan_should_accept_a_good_plan(void)
{
    static gp_plan plan;
    char error[GP_PLAN_ERROR_LEN];
    size_t len = with_crc(GOOD_BODY);
    CHECK_INT(gp_plan_read(text, len, &gp_mission_table, NULL, &plan, error), 0);
    CHECK_INT(error[0], 0);
    CHECK_INT(plan.n_states, 3);
    CHECK_INT(plan.n_components, 3);
    CHECK_INT(plan.n_assumptions, 2);
    CHECK(strcmp(plan.computer, "ts7800") == 0);
    CHECK_NEAR(plan.budget_j, 180000, 0);
    CHECK_NEAR(plan.states[1].clock_mhz, 500, 0);
    CHECK_INT(plan.states[1].n_sensors, 2);
    CHECK_INT(plan.states[1].sensors[1].sensor, 9);
    CHECK_NEAR(plan.states[1].sensors[1].on_s, 15, 0);
    CHECK_NEAR(plan.states[1].profiles[0].pitch_rad, 0.4, 0);
}

/* Fig. 2 on a vehicle with propulsion (a hybrid's thruster: its `auto` speed > 0). */
static const gp_mission *fig2_propelled(void)
{
    static gp_mission mission;
    mission = gp_mission_table;
    mission.unplanned_speed_mps = 0.45;
    return &mission;
}

void test_plan_should_read_a_yos_thrust_and_a_level_profile(void)
{
    static gp_plan plan;
    char error[GP_PLAN_ERROR_LEN];
    const gp_mission *hybrid = fig2_propelled();
    size_t len = variant("profile 0 1 0.454 230 0.31\nend\nstate s2",
                         "profile 0 1 0.454 230 0.31 4.5\nend\nstate s2");
    CHECK_INT(gp_plan_read(text, len, hybrid, NULL, &plan, error), 0);
    CHECK_NEAR(plan.states[0].profiles[0].thrust_w, 4.5, 0);
    CHECK_NEAR(plan.states[2].profiles[0].thrust_w, 0, 0);  /* left out: off */
    /* the glider has no thruster: the plan contradicts its vehicle (gp_plan_check) */
    CHECK_INT(gp_plan_read(text, len, &gp_mission_table, NULL, &plan, error), -1);
    CHECK_CONTAINS(error, "state s1: profile 0: THRUST_W 4.5 on a vehicle without a thruster");
    len = variant("profile 0 1 0.4 200 0.3", "profile 0 1 0 0 1.2");  /* cruise, level */
    CHECK_INT(gp_plan_read(text, len, hybrid, NULL, &plan, error), 0);
    CHECK_NEAR(plan.states[1].profiles[0].speed_mps, 1.2, 0);
    CHECK_INT(gp_plan_read(text, len, &gp_mission_table, NULL, &plan, error), -1);
    CHECK_CONTAINS(error, "state s2: profile 0: PITCH_RAD and BALLAST_CC 0 fly it level on a "
                   "propeller, and the vehicle has none");
}

void test_plan_should_reject_bad_files_naming_the_line(void)
{
    static const struct {
        const char *from, *to, *message;
    } rows[] = {
        {"GPPLAN 3", "GPPLAN 2",
         "line 1: plan format version '2', this runtime reads version 3"},
        {"GPPLAN 3", "GPPLAN", "line 1: expected 'GPPLAN 3'"},
        {"mission sampleMission", "mission other", "line 2: plan is for mission 'other'"},
        {"mission sampleMission", "mission 9lives", "line 2: mission name is not a NAME"},
        {"hash 5db9", "hash 6db9", "line 3: hash does not match"},
        {"hash 5db9", "hash 5DB9", "line 3: hash needs 64 lowercase hex digits"},
        {"computer ts7800 300", "computer ts7800 0", "line 4: clock 0 MHz: the board has 300, 500"},
        {"computer ts7800 300", "computer ts5500 133", "line 4: clock 133 MHz: the board has"},
        {"budget_j 180000", "budget_j 1e300", "line 5: budget_j 1e+300 exceeds 1e+10"},
        {"budget_j 180000", "budget_j 1.5e", "line 5: budget_j '1.5e' is not a NUMBER"},
        {"budget_j 180000", "budget_j .5", "line 5: budget_j '.5' is not a NUMBER"},
        {"budget_j 180000", "budget_j +5", "line 5: budget_j '+5' is not a NUMBER"},
        {"budget_j 180000", "budget_j 1e999", "line 5: budget_j 1e999 is not finite"},
        {"budget_j 180000", "budget_j 0x10", "line 5: budget_j '0x10' is not a NUMBER"},
        {"budget_j 180000", "budget_j -180000", "line 5: budget_j must be >= 0"},
        {"predicted_j 10203", "predicted_j -1", "line 6: predicted_j must be >= 0"},
        {"predicted_j 10203\n", "", "line 6: expected a 'predicted_j' line, found 'components'"},
        {"components hotel pump ctd", "components hotel pump hotel",
         "line 7: component 'hotel' named twice"},
        {"components hotel pump ctd", "components", "line 7: 'components' takes 1 to 16 fields"},
        {"components hotel pump ctd", "components 9x", "line 7: component is not a NAME"},
        {"assumptions 2", "assumptions 3", "line 11: expected a 'assume' line, found 'states'"},
        {"assumptions 2", "assumptions 256", "line 8: assumptions 256 outside 0..255"},
        {"assume s2 planned at its expect upper bound (3600 s per visit)", "assume s2",
         "line 10: 'assume' takes 2 fields, found 1"},
        {"assume mission", "assume 9mission", "line 9: SUBJECT is not a NAME"},
        {" (default)", "  (default)", "line 9: fields must be separated by exactly one space"},
        {"states 3", "states 4", "line 11: plan has 4 states, mission 'sampleMission' has 3"},
        {"states 3", "states 65", "line 11: states 65 outside 1..64"},
        {"states 3", "states -3", "line 11: states '-3' is not a COUNT"},
        {"state s1 300 600 0 1", "state s1 300 600 0 2", "line 12: 2 profiles, state 's1' has 1"},
        {"state s1 300 600 0 1", "state s1 300 0 0 1", "line 12: CYCLE_S must lie in (0, "},
        {"state s1 300 600 0 1", "state s1 300 1e300 0 1", "line 12: CYCLE_S must lie in (0, "},
        {"state s1 300 600 0 1", "state s1 1000 600 0 1", "line 12: clock 1000 MHz: the board"},
        {"predict 1000 2 19.8", "predict 1e99 2 19.8", "line 13: TIME_S 1e+99 exceeds"},
        {"state s1 300 600 0 1", "state s1 300 600 0", "line 12: 'state' takes 5 fields, found 4"},
        {"state s1 300 600 0 1\n", "state s1 300 600 0 1\npower 1 2e5\n",
         "line 13: SLEEP 1 where state 's1' does not sleep between ticks"},
        {"state s1 300 600 0 1\n", "state s1 300 600 0 1\npower 0 0\n",
         "line 13: CYCLES_PER_TICK must be > 0"},
        {"state s1 300 600 0 1\n", "state s1 300 600 0 1\npower 2 2e5\n",
         "line 13: SLEEP 2 outside 0..1"},
        {"state s1 300 600 0 1\n", "state s1 300 600 0 1\npower 0\n",
         "line 13: 'power' takes 2 fields, found 1"},
        {"predict 1000 2 19.8", "predict -1 2 19.8", "line 13: TIME_S must be >= 0"},
        {"predict 1000 2 19.8", "predict 1000 2.5 19.8", "line 13: VISITS '2.5' is not a COUNT"},
        {"predict 1000 2 19.8", "predict 1000 2", "line 13: 'predict' takes 3 fields, found 2"},
        {"energy 2410 1540 0", "energy 2410 1540", "line 14: 'energy' takes 3 fields, found 2"},
        {"energy 2410 1540 0", "energy 2410 -1540 0", "line 14: energy must be >= 0"},
        {"energy 2410 1540 0\n", "", "line 14: expected a 'energy' line, found 'profile'"},
        {"profile 0 1 0.454", "profile 0 0.9 0.454", "line 16: shares of state 's1' sum to 0.9"},
        {"profile 0 1 0.454", "profile 1 1 0.454", "line 15: profile INDEX 1 out of order"},
        {"profile 0 1 0.454", "profile 0 1 1.6", "line 15: PITCH_RAD 1.6 outside (0, pi/2)"},
        {"profile 0 1 0.454 230", "profile 0 1 0.454 0", "line 15: BALLAST_CC and SPEED_MPS"},
        {"profile 0 1 0.454 230", "profile 0 1 0.454 1e300",
         "line 12: state s1: profile 0: BALLAST_CC 1e+300 exceeds the vehicle's pump (233 cc)"},
        {"profile 0 1 0.454 230", "profile 0 1 0.454 5000",
         "line 12: state s1: profile 0: BALLAST_CC 5000 exceeds the vehicle's pump (233 cc)"},
        {"profile 0 1 0.454 230 0.31", "profile 0 1 0.454 230 40",
         "line 15: SPEED_MPS 40 exceeds 2"},
        {"profile 0 1 0.454", "profile 0 1.5 0.454", "line 15: SHARE 1.5 outside [0, 1]"},
        {"profile 0 1 0.454 230 0.31", "profile 0 1 0.454 230 0.31 -3",
         "line 15: THRUST_W -3 outside [0, 100]"},
        {"profile 0 1 0.454 230 0.31", "profile 0 1 0.454 230 0.31 3 4",
         "line 15: 'profile' takes 5 to 6 fields, found 7"},
        {"state s2", "state s9", "line 17: state 's9' where the mission has 's2'"},
        {"sensor temp 60 15", "sensor oxygen 60 15", "line 21: sensor 'oxygen' is not logged"},
        {"sensor depth 60 0\nsensor temp", "sensor temp 60 15\nsensor depth",
         "line 21: sensor 'depth' is not logged by state 's2' (or out of order)"},
        {"sensor temp 60 15", "sensor temp 60 61", "line 21: need PERIOD_S > 0"},
        {"sensor temp 60 15", "sensor temp 0 0", "line 21: need PERIOD_S > 0"},
        {"sensor temp 60 15", "sensor temp 1e12 15", "line 21: PERIOD_S 1e+12 exceeds"},
        {"end\nstate s3", "ende\nstate s3", "line 23: expected a 'end' line, found 'ende'"},
        {"end\nstate s3", "end x\nstate s3", "line 23: 'end' takes 0 fields, found 1"},
        {"budget_j 180000", "budget_j  180000", "line 5: fields must be separated by exactly"},
        {"budget_j 180000", "budget_j 180000 ", "line 5: fields must be separated by exactly"},
        {"budget_j 180000\n", "budget_j 180000\n\n", "line 6: empty line"},
        {"budget_j 180000\n", "budget_j 180000\r\n", "line 5: byte 0x0d is not allowed"},
        {"budget_j 180000", "budget_j\t180000", "line 5: byte 0x09 is not allowed"},
        {"budget_j 180000", "budget_j 18\xe9", "line 5: byte 0xe9 is not allowed"},
        {"state s3 300 600 0 1\npredict 500 1 4.7\nenergy 1205 813 0\n"
         "profile 0 1 0.454 230 0.31\nend\n",
         "state s3 300 600 0 1\npredict 500 1 4.7\nenergy 1205 813 0\n"
         "profile 0 1 0.454 230 0.31\nend\nend\n",
         "line 29: extra line after the last state block"},
        {"state s3 300 600 0 1\npredict 500 1 4.7\nenergy 1205 813 0\n"
         "profile 0 1 0.454 230 0.31\nend\n", "state s3 300 600 0 1\n",
         "line 25: missing 'predict' line (truncated file)"},
    };
    char error[GP_PLAN_ERROR_LEN];
    for (unsigned i = 0; i < sizeof rows / sizeof rows[0]; i++) {
        size_t len = variant(rows[i].from, rows[i].to);
        CHECK_INT(read_text(len, error), -1);
        CHECK_CONTAINS(error, rows[i].message);
    }
}

void test_plan_should_read_a_states_power_line_where_its_mission_sleeps(void)
{
    /* Fig. 2 with s2 asleep between ticks (`computer sleep between ticks`). */
    static gp_state states[3];
    memcpy(states, gp_mission_table.states, sizeof states);
    states[1].sleep = 1;
    gp_mission sleepy = gp_mission_table;
    sleepy.states = states;
    static char body[GP_MAX_PLAN_BYTES];
    const char *at = strstr(GOOD_BODY, "predict 1000 1 12.4");
    snprintf(body, sizeof body, "%.*spower 1 7.3e6\n%s", (int)(at - GOOD_BODY), GOOD_BODY, at);
    static gp_plan plan;
    char error[GP_PLAN_ERROR_LEN];
    CHECK_INT(gp_plan_read(text, with_crc(body), &sleepy, NULL, &plan, error), 0);
    CHECK_INT(plan.states[1].sleep, 1);
    CHECK_NEAR(plan.states[1].cycles_per_tick, 7.3e6, 0);
    CHECK_INT(plan.states[0].sleep, 0);  /* no power line: awake, the runtime's own work */
    CHECK_NEAR(plan.states[0].cycles_per_tick, 0, 0);
}

/* Fig. 2 with the bounds the code generator writes (contract.FlightLimits): the board,
 * the battery, s2's temp duty, the vehicle's pitch, ballast and speed. */
static const gp_mission *fig2_with_bounds(void)
{
    static const gp_duty_bound s2_duties[] = {{GP_SENSOR_TEMP, 0.2, 0.5}};
    static const double least_cc[] = {100};
    static const gp_state_bounds states[] = {
        {NULL, 0, least_cc}, {s2_duties, 1, least_cc}, {NULL, 0, least_cc}};
    static const gp_plan_bounds bounds = {
        .board = "ts7800", .max_budget_j = 200000, .min_pitch_rad = 0.1, .max_pitch_rad = 1.5,
        .max_speed_mps = 0.5, .min_propelled_mps = 0.4, .max_propelled_mps = 1.5,
        .min_thrust_w = 1, .max_thrust_w = 9, .states = states};
    static gp_mission mission;
    mission = gp_mission_table;
    mission.bounds = &bounds;
    return &mission;
}

static size_t none_variant(const char *from, const char *to);

void test_plan_should_be_held_to_its_missions_bounds(void)
{
    static const struct {
        const char *from, *to, *error;
    } cases[] = {
        {"computer ts7800", "computer ts5500",
         "line 4: computer ts5500: the mission flies on board ts7800 (plan again with "
         "--computer ts7800)"},
        {"budget_j 180000", "budget_j 300000",
         "line 5: budget_j 300000 J exceeds the mission's battery less its reserve (200000 J)"},
        {"predicted_j 10203", "predicted_j 0",
         "line 6: predicted_j 0 J is not the sum of its states' energy (10203 J)"},
        {"budget_j 180000", "budget_j 10000", "line 6: predicted_j 10203 J exceeds budget_j 10000 J"},
        {"sensor temp 60 15", "sensor temp 60 0",
         "line 17: state s2: sensor temp: duty 0 outside the mission's [0.2, 0.5]"},
        {"sensor temp 60 15", "sensor temp 60 60",
         "line 17: state s2: sensor temp: duty 1 outside the mission's [0.2, 0.5]"},
        {"profile 0 1 0.454 230 0.31", "profile 0 1 0.05 230 0.31",
         "line 12: state s1: profile 0: PITCH_RAD 0.05 outside the vehicle's (0.1, 1.5) rad"},
        {"profile 0 1 0.454 230 0.31", "profile 0 1 0.454 50 0.31",
         "line 12: state s1: profile 0: BALLAST_CC 50 does not fly it: the vehicle needs more "
         "than 100 cc"},
        {"profile 0 1 0.454 230 0.31", "profile 0 1 0.454 230 0.6",
         "line 12: state s1: profile 0: SPEED_MPS 0.6 exceeds the vehicle's fastest glide "
         "(0.5 m/s)"},
    };
    static gp_plan plan;
    char error[GP_PLAN_ERROR_LEN];
    const gp_mission *mission = fig2_with_bounds();
    CHECK_INT(gp_plan_read(text, with_crc(GOOD_BODY), mission, NULL, &plan, error), 0);
    CHECK_INT(gp_plan_check(&plan, mission, error), 0);
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        CHECK_INT(gp_plan_read(text, variant(cases[i].from, cases[i].to), mission, NULL, &plan,
                               error), -1);
        CHECK_CONTAINS(error, cases[i].error);
    }
    /* a plan for no board names no board to compare: it flies on this one */
    CHECK_INT(gp_plan_read(text, none_variant("", ""), mission, NULL, &plan, error), 0);
    /* on a hybrid, a thruster-assisted yo outruns the fastest glide, and a level profile
     * (propelled) has no pitch or volume to hold to the glide's */
    static gp_mission hybrid;
    hybrid = *mission;
    hybrid.unplanned_speed_mps = 0.45;
    CHECK_INT(gp_plan_read(text, variant("profile 0 1 0.454 230 0.31",
                                         "profile 0 1 0.454 230 0.6 4.5"),
                           &hybrid, NULL, &plan, error), 0);
    CHECK_INT(gp_plan_read(text, variant("profile 0 1 0.454 230 0.31", "profile 0 1 0 0 1.2"),
                           &hybrid, NULL, &plan, error), 0);
    /* ... held to its rating: the propulsion's speeds, the thruster's power command */
    static const struct {
        const char *to, *error;
    } rated[] = {
        {"profile 0 1 0 0 1.6", "line 12: state s1: profile 0: SPEED_MPS 1.6 outside the "
         "vehicle's propulsion (0.4-1.5 m/s)"},
        {"profile 0 1 0 0 0.3", "line 12: state s1: profile 0: SPEED_MPS 0.3 outside the "
         "vehicle's propulsion (0.4-1.5 m/s)"},
        {"profile 0 1 0.454 230 0.6 12", "line 12: state s1: profile 0: THRUST_W 12 outside "
         "the vehicle's thruster (1-9 W)"},
        {"profile 0 1 0.454 230 0.6 0.5", "line 12: state s1: profile 0: THRUST_W 0.5 outside "
         "the vehicle's thruster (1-9 W)"},
    };
    for (size_t i = 0; i < sizeof rated / sizeof rated[0]; i++) {
        CHECK_INT(gp_plan_read(text, variant("profile 0 1 0.454 230 0.31", rated[i].to),
                               &hybrid, NULL, &plan, error), -1);
        CHECK_CONTAINS(error, rated[i].error);
    }
    CHECK_INT(gp_plan_read(text, variant("profile 0 1 0.454 230 0.31",
                                         "profile 0 1 0.454 230 0.6 9"),
                           &hybrid, NULL, &plan, error), 0);
}

/* `body` with its first `from` replaced by `to`, in place (`from` must be there). */
static void replace_in(char *body, const char *from, const char *to)
{
    static char rest[GP_MAX_PLAN_BYTES];
    char *at = strstr(body, from);
    if (at == NULL) {
        gp_test_fail(__FILE__, __LINE__, from);
        return;
    }
    snprintf(rest, sizeof rest, "%s", at + strlen(from));
    snprintf(at, GP_MAX_PLAN_BYTES - (size_t)(at - body), "%s%s", to, rest);
}

/* The good plan made for `computer none` (every clock 0: no clock to set) with the
 * first `from` replaced by `to` ("" for none), checksummed. */
static size_t none_variant(const char *from, const char *to)
{
    static char body[GP_MAX_PLAN_BYTES];
    snprintf(body, sizeof body, "%s", GOOD_BODY);
    replace_in(body, "computer ts7800 300", "computer none 0");
    replace_in(body, "state s1 300", "state s1 0");
    replace_in(body, "state s2 500", "state s2 0");
    replace_in(body, "state s3 300", "state s3 0");
    if (*from) {
        replace_in(body, from, to);
    }
    return with_crc(body);
}

/* Fig. 2 compiled for no board (`computer none`): its one clock is 0. */
static const gp_mission *fig2_for_no_board(void)
{
    static const double clocks_mhz[] = {0.0};
    static gp_mission mission;
    mission = gp_mission_table;
    mission.clocks_mhz = clocks_mhz;
    mission.n_clocks = 1;
    return &mission;
}

void test_plan_should_accept_computer_none_on_any_build(void)
{
    const gp_mission *builds[] = {&gp_mission_table, fig2_for_no_board()};
    static gp_plan plan;
    char error[GP_PLAN_ERROR_LEN];
    for (int i = 0; i < 2; i++) {
        CHECK_INT(gp_plan_read(text, none_variant("", ""), builds[i], NULL, &plan, error), 0);
        CHECK_INT(error[0], 0);
        CHECK(strcmp(plan.computer, "none") == 0);
        CHECK_NEAR(plan.clock_mhz, 0, 0);
        CHECK_NEAR(plan.states[1].clock_mhz, 0, 0);  /* the runtime leaves the clock alone */
    }
}

void test_plan_should_reject_clocks_on_computer_none_and_boards_on_its_build(void)
{
    static gp_plan plan;
    char error[GP_PLAN_ERROR_LEN];
    CHECK_INT(read_text(none_variant("computer none 0", "computer none 300"), error), -1);
    CHECK_CONTAINS(error, "line 4: clock 300 MHz: computer none has no clock to set");
    CHECK_INT(read_text(none_variant("state s2 0", "state s2 500"), error), -1);
    CHECK_CONTAINS(error, "line 17: clock 500 MHz: computer none has no clock to set");
    const gp_mission *none = fig2_for_no_board();
    CHECK_INT(gp_plan_read(text, with_crc(GOOD_BODY), none, NULL, &plan, error), -1);
    CHECK_CONTAINS(error, "line 4: clock 300 MHz: the mission names no board (computer none)");
    size_t len = variant("computer ts7800 300", "computer ts7800 0");
    CHECK_INT(gp_plan_read(text, len, none, NULL, &plan, error), -1);
    CHECK_CONTAINS(error, "line 4: clock 0 MHz: the mission names no board (computer none)");
}

void test_plan_should_reject_a_file_of_only_its_checksum_line(void)
{
    /* Found by fuzz/fuzz_plan.c: the reader ran past the end of the text. */
    char error[GP_PLAN_ERROR_LEN];
    CHECK_INT(read_text(with_crc(""), error), -1);
    CHECK_CONTAINS(error, "line 1: the plan ends before this line (truncated file)");
}

void test_plan_should_reject_an_overlong_line(void)
{
    char long_name[300];
    memset(long_name, 'x', 260);
    memcpy(long_name, "computer ", 9);
    long_name[260] = '\0';
    char error[GP_PLAN_ERROR_LEN];
    CHECK_INT(read_text(variant("computer ts7800 300", long_name), error), -1);
    CHECK_CONTAINS(error, "line 4: longer than 255 bytes");
}

void test_plan_should_reject_truncated_and_corrupted_files(void)
{
    char error[GP_PLAN_ERROR_LEN];
    size_t len = with_crc(GOOD_BODY);
    CHECK_INT(read_text(len - 1, error), -1);   /* final LF missing */
    CHECK_CONTAINS(error, "no final LF (truncated file)");
    CHECK_INT(read_text(strlen(GOOD_BODY), error), -1);  /* crc32 line lost */
    CHECK_CONTAINS(error, "line 28: the last line is not 'crc32 HEX8' (truncated file)");
    CHECK_INT(read_text(0, error), -1);
    CHECK_CONTAINS(error, "empty file");
    for (size_t cut = 1; cut < len; cut += 7) {  /* every cut is refused, none crashes */
        CHECK_INT(read_text(cut, error), -1);
    }
    text[20] = 'X';  /* a changed byte the checksum catches */
    CHECK_INT(read_text(len, error), -1);
    CHECK_CONTAINS(error, "line 29: checksum mismatch");
    len = with_crc(GOOD_BODY);
    text[len - 2] = 'g';
    CHECK_INT(read_text(len, error), -1);
    CHECK_CONTAINS(error, "crc32 needs 8 lowercase hex digits");
}

void test_plan_should_reject_a_file_over_64_kib(void)
{
    static char big[GP_MAX_PLAN_BYTES + 2];
    char error[GP_PLAN_ERROR_LEN];
    static gp_plan plan;
    memset(big, 'a', sizeof big);
    CHECK_INT(gp_plan_read(big, sizeof big, &gp_mission_table, NULL, &plan, error), -1);
    CHECK_CONTAINS(error, "exceeds 65536");
}

void test_plan_should_keep_the_last_good_plan_on_rejection(void)
{
    static gp_plan plan;
    char error[GP_PLAN_ERROR_LEN];
    CHECK_INT(gp_plan_read(text, with_crc(GOOD_BODY), &gp_mission_table, NULL, &plan, error), 0);
    size_t len = variant("budget_j 180000", "budget_j 20000");
    text[30] ^= 1;  /* and break its checksum */
    CHECK_INT(gp_plan_read(text, len, &gp_mission_table, NULL, &plan, error), -1);
    CHECK_NEAR(plan.budget_j, 180000, 0);
}

void test_random_bytes_should_never_crash_the_plan_reader(void)
{
    static gp_plan plan;
    static char body[sizeof GOOD_BODY];
    char error[GP_PLAN_ERROR_LEN];
    unsigned seed = 2024;
    for (int round = 0; round < 3000; round++) {
        memcpy(body, GOOD_BODY, sizeof GOOD_BODY);
        int flips = 1 + (int)(gp_test_random(&seed) % 4);
        for (int i = 0; i < flips; i++) {
            char byte = (char)(gp_test_random(&seed) & 0xFF);
            body[gp_test_random(&seed) % (sizeof GOOD_BODY - 1)] = byte ? byte : '\n';
        }
        /* Damage under a valid checksum reaches the line rules; without, the checksum. */
        size_t len = with_crc(round % 2 ? body : GOOD_BODY);
        if (round % 2 == 0) {
            memcpy(text, body, sizeof GOOD_BODY - 1);
        }
        int result = gp_plan_read(text, len, &gp_mission_table, NULL, &plan, error);
        CHECK(result == 0 || strncmp(error, "line ", 5) == 0);
    }
}

/* ---- signed plans ---------------------------------------------------------------- */

/* Append `seq N` and the `hmac` line, signed with `key`, to the `len` bytes in `text`. */
static size_t with_signature(size_t len, unsigned long seq, const uint8_t *key)
{
    len += (size_t)sprintf(text + len, "seq %lu\n", seq);
    gp_hmac_sha256 mac;
    uint8_t tag[GP_SHA256_SIZE];
    gp_hmac_sha256_init(&mac, key, GP_PLAN_KEY_BYTES);
    gp_hmac_sha256_update(&mac, text, len);
    gp_hmac_sha256_final(&mac, tag);
    len += (size_t)sprintf(text + len, "hmac ");
    for (int i = 0; i < GP_SHA256_SIZE; i++) {
        len += (size_t)sprintf(text + len, "%02x", tag[i]);
    }
    return len + (size_t)sprintf(text + len, "\n");
}

static void test_key(gp_plan_auth *auth)
{
    memset(auth, 0, sizeof *auth);
    for (int i = 0; i < GP_PLAN_KEY_BYTES; i++) {
        auth->key[i] = (uint8_t)i;
    }
}

void test_signed_plan_should_carry_the_tag_gliderplan_plan_sign_writes(void)
{
    /* The tag Python's hmac module gives for this plan, seq 7, key 00 01 .. 1f: the
     * runtime and `gliderplan plan --sign` agree on what is signed. */
    static gp_plan plan;
    static gp_plan_auth auth;
    char error[GP_PLAN_ERROR_LEN];
    test_key(&auth);
    size_t len = with_crc(GOOD_BODY);
    len += (size_t)sprintf(text + len, "seq 7\nhmac %s\n",
                           "dce9e85f51f7f12a86519c60f3ed90a81f0698963456ccb396f785e9b036ec04");
    CHECK_INT(gp_plan_read(text, len, &gp_mission_table, &auth, &plan, error), 0);
    CHECK_INT(plan.is_signed, 1);
    CHECK_INT(plan.seq, 7);
    CHECK_INT(plan.tag[0], 0xdc);
    CHECK_INT(gp_plan_read(text, len, &gp_mission_table, NULL, &plan, error), 0);  /* no key */
    auth.key[31] ^= 1;  /* another vehicle's key */
    CHECK_INT(gp_plan_read(text, len, &gp_mission_table, &auth, &plan, error), -1);
    CHECK_CONTAINS(error, "line 31: the signature does not match");
}

void test_signed_plan_should_refuse_unsigned_tampered_replayed_and_foreign_plans(void)
{
    static gp_plan plan;
    static gp_plan_auth auth;
    char error[GP_PLAN_ERROR_LEN];
    test_key(&auth);
    CHECK_INT(gp_plan_read(text, with_crc(GOOD_BODY), &gp_mission_table, &auth, &plan, error), -1);
    CHECK_CONTAINS(error, "line 29: the plan is not signed, and this runtime holds a key");

    size_t len = with_signature(with_crc(GOOD_BODY), 5, auth.key);
    CHECK_INT(gp_plan_read(text, len, &gp_mission_table, &auth, &plan, error), 0);
    auth.last_seq = plan.seq;
    memcpy(auth.last_tag, plan.tag, sizeof plan.tag);
    /* the plan in force again (a retransmission) is accepted */
    CHECK_INT(gp_plan_read(text, len, &gp_mission_table, &auth, &plan, error), 0);

    /* tampered: a value changed and the CRC recomputed, the tag left as it was */
    static char signed_text[sizeof text];
    memcpy(signed_text, text, len);
    size_t tail = len - strlen(strstr(signed_text, "seq 5\n"));
    size_t body = variant("profile 0 1 0.454 230", "profile 0 1 0.454 231");
    memmove(text + body, signed_text + tail, len - tail);
    CHECK_INT(gp_plan_read(text, body + len - tail, &gp_mission_table, &auth, &plan, error), -1);
    CHECK_CONTAINS(error, "line 31: the signature does not match: the plan was changed");
    CHECK_INT(plan.seq, 5);  /* the last good plan stays */

    CHECK_INT(gp_plan_read(text, with_signature(with_crc(GOOD_BODY), 4, auth.key),
                           &gp_mission_table, &auth, &plan, error), -1);
    CHECK_CONTAINS(error, "line 30: seq 4 is older than the plan in force (seq 5): a replayed");
    len = with_signature(variant("budget_j 180000", "budget_j 20000"), 5, auth.key);
    CHECK_INT(gp_plan_read(text, len, &gp_mission_table, &auth, &plan, error), -1);
    CHECK_CONTAINS(error, "line 30: seq 5 is the plan in force's, but this is another plan");
    CHECK_INT(gp_plan_read(text, with_signature(variant("hash 5db9", "hash 6db9"), 6, auth.key),
                           &gp_mission_table, &auth, &plan, error), -1);
    CHECK_CONTAINS(error, "line 3: hash does not match");  /* signed, for another mission */
    len = with_signature(variant("budget_j 180000", "budget_j 20000"), 6, auth.key);
    CHECK_INT(gp_plan_read(text, len, &gp_mission_table, &auth, &plan, error), 0);
    CHECK_INT(plan.seq, 6);
    CHECK_NEAR(plan.budget_j, 20000, 0);
}

void test_signed_plan_should_have_a_well_formed_tail(void)
{
    static gp_plan plan;
    char error[GP_PLAN_ERROR_LEN];
    static const struct {
        const char *tail, *message;
    } rows[] = {
        {"seq 0\nhmac " "00000000000000000000000000000000" "00000000000000000000000000000000\n",
         "line 30: seq '0' is not a COUNT from 1"},
        {"seq 4294967296\nhmac " "0000000000000000000000000000000000000000000000000000000000000000\n",
         "line 30: seq 4294967296 exceeds 4294967295"},
        {"seq 07\nhmac " "0000000000000000000000000000000000000000000000000000000000000000\n",
         "line 30: seq '07' is not a COUNT from 1"},
        {"hmac 0000000000000000000000000000000000000000000000000000000000000000\n",
         "line 29: a signed plan needs 'seq COUNT' before its 'hmac' line"},
        {"seq 7\nhmac 00\n", "line 31: hmac needs 64 lowercase hex digits"},
        {"seq 7\n", "line 30: the last line is not 'crc32 HEX8'"},
    };
    for (unsigned i = 0; i < sizeof rows / sizeof rows[0]; i++) {
        size_t len = with_crc(GOOD_BODY);
        len += (size_t)sprintf(text + len, "%s", rows[i].tail);
        CHECK_INT(gp_plan_read(text, len, &gp_mission_table, NULL, &plan, error), -1);
        CHECK_CONTAINS(error, rows[i].message);
    }
    CHECK_INT(gp_plan_read("hmac x\n", 7, &gp_mission_table, NULL, &plan, error), -1);
    CHECK_INT(gp_plan_read("seq 1\nhmac x\n", 13, &gp_mission_table, NULL, &plan, error), -1);
}

/* ---- schedule ------------------------------------------------------------------ */

static const gp_profile two_profiles[] = {{GP_PROFILE_YO, 0, NULL, 0.0},
                                          {GP_PROFILE_HOVER, 0, NULL, 0.0}};
static const uint8_t logged[] = {0, 1, 9, 12};  /* missiontime, depth, temp, oxygen */
static const gp_state scheduled = {
    "s", {GP_ROUTE_NOHEADING, 0, 0, NULL}, two_profiles, 2, logged, 4, NULL, 0, 0, 0, 0x1203, 0,
};

void test_schedule_without_a_plan_should_power_every_logged_sensor(void)
{
    gp_schedule_now now;
    gp_schedule(&scheduled, NULL, 1234, 230, &now);
    CHECK_INT(now.profile, 0);
    CHECK_INT(now.sensor_power, (1u << 0) | (1u << 1) | (1u << 9) | (1u << 12));
    CHECK(isnan(now.pitch_rad));
    CHECK_NEAR(now.ballast_cc, 230, 0);
}

void test_schedule_should_alternate_profiles_and_power_windows(void)
{
    gp_plan_state ps = {
        .clock_mhz = 300, .cycle_s = 600, .n_sensors = 2, .n_profiles = 2,
        .sensors = {{1, 60, 0}, {9, 60, 15}},   /* depth "off": no device, stays on */
        .profiles = {{0.75, 0.4, 200, 0.3}, {0.25, 0.3, 150, 0.25}},
    };
    static const struct { double t_in; int profile; int temp_on; double pitch; } rows[] = {
        {0, 0, 1, 0.4}, {14.9, 0, 1, 0.4}, {15, 0, 0, 0.4}, {59.9, 0, 0, 0.4},
        {60, 0, 1, 0.4}, {449.9, 0, 0, 0.4}, {450, 1, 0, 0.3}, {599.9, 1, 0, 0.3},
        {600, 0, 1, 0.4}, {1050, 1, 0, 0.3}, {1080, 1, 1, 0.3},
    };
    for (unsigned i = 0; i < sizeof rows / sizeof rows[0]; i++) {
        gp_schedule_now now;
        gp_schedule(&scheduled, &ps, rows[i].t_in, 230, &now);
        CHECK_INT(now.profile, rows[i].profile);
        CHECK_INT((now.sensor_power >> 9) & 1u, rows[i].temp_on);
        CHECK_INT(now.sensor_power & 0x1003u, 0x1003u);  /* missiontime, depth, oxygen */
        CHECK_NEAR(now.pitch_rad, rows[i].pitch, 0);
        CHECK_NEAR(now.ballast_cc, rows[i].profile ? 150 : 200, 0);
    }
}

void test_schedule_should_give_the_remainder_to_the_last_nonzero_share(void)
{
    gp_plan_state ps = {.cycle_s = 100, .n_profiles = 2,
                        .profiles = {{0.5, 0.4, 200, 0.3}, {0.4999999, 0.3, 150, 0.25}}};
    gp_schedule_now now;
    gp_schedule(&scheduled, &ps, 99.99999, 230, &now);
    CHECK_INT(now.profile, 1);
    gp_plan_state only_second = {.cycle_s = 100, .n_profiles = 2,
                                 .profiles = {{0, 0.4, 200, 0.3}, {1, 0.3, 150, 0.25}}};
    static const double times_s[] = {0, 50, 99.99999, 100, 3600.25, 1e9 + 0.5};
    for (unsigned i = 0; i < sizeof times_s / sizeof times_s[0]; i++) {
        gp_schedule(&scheduled, &only_second, times_s[i], 230, &now);
        CHECK_INT(now.profile, 1);
        CHECK_NEAR(now.ballast_cc, 150, 0);
    }
}
