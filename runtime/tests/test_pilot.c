/* Flight profiles of docs/pilot.md: yo leg turns as a trace table, and the
 * thermocline trackers on clean and noisy casts.
 *
 *   yo:    DIVE --(depth >= max || altitude <= stop)--> CLIMB --(depth <= min)--> DIVE
 *   cast:  20 degC above 15 m, 10 degC below 21 m, linear in between
 */
#include <math.h>

#include "gp_frame.h"
#include "gp_pilot.h"
#include "gp_test.h"

static gp_profile_input yo_input(double min, double max)
{
    return (gp_profile_input){.kind = GP_PROFILE_YO, .args = {min, max, 0.4, 0.5},
                              .plan_pitch_rad = NAN, .ballast_cc = 230};
}

void test_yo_should_turn_at_its_depths(void)
{
    static const struct {
        double depth;
        double target, pitch, ballast;
        uint8_t flags;
    } rows[] = {
        {3.0, 10, -0.4, -230, 0},
        {9.9, 10, -0.4, -230, 0},
        {10.0, 5, 0.5, 230, GP_FLAG_CLIMBING},
        {7.0, 5, 0.5, 230, GP_FLAG_CLIMBING},
        {11.0, 5, 0.5, 230, GP_FLAG_CLIMBING},  /* climbing leg ignores max */
        {5.0, 10, -0.4, -230, 0},
        {4.0, 10, -0.4, -230, 0},               /* diving leg ignores min */
    };
    static const unsigned halfcycle[] = {1, 1, 2, 2, 2, 3, 3};  /* the leg flown */
    gp_profile_input in = yo_input(5, 10);
    gp_pilot pilot;
    gp_pilot_command out;
    gp_pilot_enter(&pilot, &in, rows[0].depth, NAN);
    CHECK_INT(pilot.halfcycle, 1);
    for (unsigned i = 0; i < sizeof rows / sizeof rows[0]; i++) {
        gp_pilot_step(&pilot, &in, rows[i].depth, NAN, NAN, &out);
        CHECK_NEAR(out.depth_target_m, rows[i].target, 0);
        CHECK_NEAR(out.pitch_rad, rows[i].pitch, 1e-12);
        CHECK_NEAR(out.ballast_cc, rows[i].ballast, 0);
        CHECK_INT(out.flags, rows[i].flags);
        CHECK_INT(pilot.halfcycle, halfcycle[i]);
    }
    gp_profile_input surface = {.kind = GP_PROFILE_SURFACE, .plan_pitch_rad = NAN};
    gp_pilot_enter(&pilot, &surface, 4.0, NAN);
    CHECK_INT(pilot.halfcycle, 0);  /* not a yo */
}

void test_yo_should_start_climbing_below_max_and_use_planned_pitch(void)
{
    gp_profile_input in = yo_input(5, 10);
    in.plan_pitch_rad = 0.3;
    gp_pilot pilot;
    gp_pilot_command out;
    gp_pilot_enter(&pilot, &in, 12.0, NAN);
    CHECK_INT(pilot.leg, GP_LEG_CLIMB);
    gp_pilot_step(&pilot, &in, 12.0, NAN, NAN, &out);
    CHECK_NEAR(out.pitch_rad, 0.3, 0);
    gp_pilot_step(&pilot, &in, 5.0, NAN, NAN, &out);
    CHECK_NEAR(out.pitch_rad, -0.3, 0);
}

void test_yo_should_turn_a_dive_at_its_altimeter_stop(void)
{
    static const struct {
        double depth, altitude;
        double target;
        unsigned halfcycle;
    } rows[] = {
        {3.0, 40.0, 50, 1},
        {30.0, NAN, 50, 1},   /* the floor out of the altimeter's range: no stop */
        {35.0, 4.01, 50, 1},
        {35.5, 4.0, 3, 2},    /* at the stop: climb, 14 m above max */
        {33.0, 2.0, 3, 2},    /* a climbing leg ignores the altimeter */
        {3.0, 40.0, 50, 3},
        {20.0, 3.0, 3, 4},    /* below the stop */
    };
    gp_profile_input in = yo_input(3, 50);
    in.args[GP_YO_ALTITUDE_ARG] = 4.0;
    gp_pilot pilot;
    gp_pilot_command out;
    gp_pilot_enter(&pilot, &in, rows[0].depth, rows[0].altitude);
    for (unsigned i = 0; i < sizeof rows / sizeof rows[0]; i++) {
        gp_pilot_step(&pilot, &in, rows[i].depth, NAN, rows[i].altitude, &out);
        CHECK_NEAR(out.depth_target_m, rows[i].target, 0);
        CHECK_INT(pilot.halfcycle, rows[i].halfcycle);
    }
    gp_pilot_enter(&pilot, &in, 20.0, 2.0);  /* entered at the stop: climbing */
    CHECK_INT(pilot.leg, GP_LEG_CLIMB);
    in.args[GP_YO_ALTITUDE_ARG] = 0.0;      /* 0: no altimeter stop */
    gp_pilot_enter(&pilot, &in, 20.0, 0.5);
    gp_pilot_step(&pilot, &in, 20.0, NAN, 0.5, &out);
    CHECK_INT(pilot.leg, GP_LEG_DIVE);
}

void test_thermotrackyo_should_turn_a_dive_at_its_altimeter_stop(void)
{
    gp_profile_input in = {.kind = GP_PROFILE_THERMOTRACKYO,
                           .args = {2, 60, 0.4, 0.4, 3, 6, 5.0}, .plan_pitch_rad = NAN,
                           .ballast_cc = 230};
    gp_pilot pilot;
    gp_pilot_command out;
    gp_pilot_enter(&pilot, &in, 10.0, 30.0);
    CHECK_INT(gp_pilot_step(&pilot, &in, 10.0, 15.0, 30.0, &out), 0);
    CHECK_INT(gp_pilot_step(&pilot, &in, 35.0, 15.0, 5.0, &out) & GP_PILOT_TURNED,
              GP_PILOT_TURNED);
    CHECK_INT(pilot.leg, GP_LEG_CLIMB);
    CHECK_NEAR(out.depth_target_m, 2, 0);
}

void test_surface_and_hover_should_command_fixed_attitudes(void)
{
    gp_profile_input surface = {.kind = GP_PROFILE_SURFACE, .plan_pitch_rad = NAN,
                                .ballast_cc = 200};
    gp_profile_input hover = {.kind = GP_PROFILE_HOVER, .args = {12.5}, .plan_pitch_rad = NAN,
                              .ballast_cc = 200};
    gp_pilot pilot;
    gp_pilot_command out;
    gp_pilot_enter(&pilot, &surface, 3, NAN);
    gp_pilot_step(&pilot, &surface, 3, NAN, NAN, &out);
    CHECK_NEAR(out.depth_target_m, 0, 0);
    CHECK_NEAR(out.pitch_rad, GP_SURFACE_PITCH_RAD, 0);
    CHECK_NEAR(out.ballast_cc, 200, 0);
    CHECK(out.flags & GP_FLAG_SURFACE);
    gp_pilot_enter(&pilot, &hover, 3, NAN);
    gp_pilot_step(&pilot, &hover, 3, NAN, NAN, &out);
    CHECK_NEAR(out.depth_target_m, 12.5, 0);
    CHECK_NEAR(out.pitch_rad, 0, 0);
    CHECK_NEAR(out.ballast_cc, 0, 0);
}

/* ---- thermocline tracking ------------------------------------------------------ */

static double cast_temp(double depth)
{
    if (depth <= 15) {
        return 20;
    }
    if (depth >= 21) {
        return 10;
    }
    return 20 - (depth - 15) * 10.0 / 6.0;
}

typedef struct {
    int detections;
    double lo, hi;      /* band after the dive */
} dive_result;

/* Dive 0 -> 39 m at 0.25 m per tick; noise_c: alternating +-noise plus jitter. */
static dive_result dive(int naive, double noise_c)
{
    gp_profile_input in = {.kind = GP_PROFILE_THERMOTRACKYO, .args = {5, 40, 0.4, 0.4, 3, 4},
                           .plan_pitch_rad = NAN, .ballast_cc = 230, .naive = (uint8_t)naive};
    gp_pilot pilot;
    gp_pilot_command out;
    dive_result result = {0, 0, 0};
    unsigned seed = 12345;
    gp_pilot_enter(&pilot, &in, 0, NAN);
    for (int i = 0; i < 156; i++) {
        double depth = 0.25 * i;
        double jitter = ((double)(gp_test_random(&seed) % 1000) / 1000.0 - 0.5) * 0.2 * noise_c;
        double temp = cast_temp(depth) + (i % 2 ? noise_c : -noise_c) + jitter;
        if (gp_pilot_step(&pilot, &in, depth, temp, NAN, &out) & GP_PILOT_DETECTED) {
            result.detections++;
            result.lo = pilot.lo_m;
            result.hi = pilot.hi_m;
        }
        if (pilot.leg != GP_LEG_DIVE) {
            break;
        }
    }
    return result;
}

void test_naive_tracker_should_detect_a_clean_cast(void)
{
    dive_result r = dive(1, 0.0);
    CHECK(r.detections >= 1);
    CHECK(r.lo >= 13 && r.hi <= 23);
}

void test_naive_tracker_should_never_detect_a_noisy_cast(void)
{
    /* the paper's first sea trial: noise resets the window on every other reading */
    CHECK_INT(dive(1, 0.5).detections, 0);
}

void test_robust_tracker_should_detect_clean_and_noisy_casts(void)
{
    static const double noise[] = {0.0, 0.5, 0.8};
    for (int i = 0; i < 3; i++) {
        dive_result r = dive(0, noise[i]);
        CHECK(r.detections >= 1);
        double middle = (r.lo + r.hi) / 2;
        CHECK(middle >= 14 && middle <= 22);  /* the band sits on the thermocline */
        CHECK_NEAR(r.hi - r.lo, 4.0, 1e-9);   /* depth_threshold wide */
    }
}

void test_tracker_should_turn_at_the_band_and_reset_a_lost_band(void)
{
    gp_profile_input in = {.kind = GP_PROFILE_THERMOTRACKYO, .args = {5, 40, 0.4, 0.4, 3, 4},
                           .plan_pitch_rad = NAN, .ballast_cc = 230};
    gp_pilot pilot;
    gp_pilot_command out;
    gp_pilot_enter(&pilot, &in, 0, NAN);
    double depth = 0;
    for (int i = 0; i < 200 && pilot.leg == GP_LEG_DIVE; i++, depth += 0.25) {
        gp_pilot_step(&pilot, &in, depth, cast_temp(depth), NAN, &out);
    }
    CHECK_INT(pilot.leg, GP_LEG_CLIMB);
    CHECK(depth < 25);           /* turned at the band's bottom, not at 40 m */
    double hi = pilot.hi_m;
    CHECK(hi < 40);
    /* climb through water of one temperature: no detection; the turn forgets the band */
    for (int i = 0; i < 400 && pilot.leg == GP_LEG_CLIMB; i++, depth -= 0.25) {
        gp_pilot_step(&pilot, &in, depth, 15.0, NAN, &out);
    }
    CHECK_INT(pilot.leg, GP_LEG_DIVE);
    CHECK_NEAR(pilot.lo_m, 5, 0);
    CHECK_NEAR(pilot.hi_m, 40, 0);
    CHECK_NEAR(out.depth_target_m, 40, 0);
}

void test_tracker_should_ignore_missing_readings(void)
{
    gp_profile_input in = {.kind = GP_PROFILE_THERMOTRACKYO, .args = {5, 40, 0.4, 0.4, 3, 4},
                           .plan_pitch_rad = NAN, .ballast_cc = 230};
    gp_pilot pilot;
    gp_pilot_command out;
    gp_pilot_enter(&pilot, &in, 0, NAN);
    for (int i = 0; i < 100; i++) {
        CHECK_INT(gp_pilot_step(&pilot, &in, 1.0, NAN, NAN, &out), 0);
    }
    CHECK_INT(pilot.n_window, 0);
}

/* A band end a variable set to NaN (docs/pilot.md): a detection keeps it NaN, as the
 * reference's max(min, lo) and min(max, hi) do, never the detected depth in its place. */
void test_tracker_should_keep_a_nan_band_end_on_detection(void)
{
    gp_profile_input in = {.kind = GP_PROFILE_THERMOTRACKYO, .args = {5, NAN, 0.4, 0.4, 3, 4},
                           .plan_pitch_rad = NAN, .ballast_cc = 230};
    gp_pilot pilot;
    gp_pilot_command out;
    gp_pilot_enter(&pilot, &in, 0, NAN);
    int detected = 0;
    for (int i = 0; i < 156 && !detected; i++) {
        double depth = 0.25 * i;
        detected = gp_pilot_step(&pilot, &in, depth, cast_temp(depth), NAN, &out)
                   & GP_PILOT_DETECTED;
    }
    CHECK(detected);
    CHECK(pilot.lo_m > 5 && pilot.lo_m < 25);  /* a number bound: the detected band's */
    CHECK(isnan(pilot.hi_m));
    CHECK(isnan(out.depth_target_m));          /* the dive's target: the envelope's to end */
}

/* The robust tracker skips its walk of the window on a tick that keeps every reading
 * (its summary: shallowest, deepest, warmest, coldest). Against the same tracker made
 * to walk the window every tick, on random casts that wander up and down (readings
 * dropped from the middle of the window), repeat temperatures (ties: the first of
 * equals) and fill the window (its oldest reading dropped): the same commands, band,
 * detections and window, tick for tick. */
void test_robust_tracker_should_skip_its_walk_only_where_it_changes_nothing(void)
{
    unsigned seed = 99;
    int skipped = 0, walked = 0;
    for (int cast = 0; cast < 60; cast++) {
        double depth_threshold = 1 + gp_test_random(&seed) % 12;
        double temp_threshold = cast % 3 == 0 ? 1.5 : 50;  /* some detect, some fill up */
        gp_profile_input in = {.kind = GP_PROFILE_THERMOTRACKYO,
                               .args = {0, 200, 0.4, 0.4, temp_threshold, depth_threshold},
                               .plan_pitch_rad = NAN, .ballast_cc = 230};
        gp_pilot summarized, walking;
        gp_pilot_command out_s, out_w;
        double depth = 50;
        gp_pilot_enter(&summarized, &in, depth, NAN);
        gp_pilot_enter(&walking, &in, depth, NAN);
        for (int tick = 0; tick < 300; tick++) {
            depth += ((double)(gp_test_random(&seed) % 41) - 15) / 10.0;  /* -1.5..+2.5 m */
            double temp = 0.5 * (double)(gp_test_random(&seed) % 9) + (depth < 60 ? 10 : 0);
            int before = summarized.n_window;
            walking.summarized = 0;  /* forget the summary: walk the window */
            int r_s = gp_pilot_step(&summarized, &in, depth, temp, NAN, &out_s);
            int r_w = gp_pilot_step(&walking, &in, depth, temp, NAN, &out_w);
            /* a reading dropped (walked), or all kept and one more (skipped) */
            walked += r_s == 0 && summarized.n_window > 0 && summarized.n_window <= before;
            skipped += r_s == 0 && summarized.n_window == before + 1;
            CHECK_INT(r_s, r_w);
            CHECK(out_s.depth_target_m == out_w.depth_target_m);
            CHECK(summarized.lo_m == walking.lo_m && summarized.hi_m == walking.hi_m);
            CHECK_INT(summarized.n_window, walking.n_window);
            CHECK(memcmp(summarized.window, walking.window,
                         summarized.n_window * sizeof summarized.window[0]) == 0);
        }
    }

    CHECK(skipped > 1000 && walked > 1000);  /* both paths taken, many times */
}

void test_cruise_and_altitude_should_fly_level_at_their_speed(void)
{
    /* cruise(12, 1.1) without a plan, then with a plan's 0.9 m/s */
    gp_profile_input cruise = {.kind = GP_PROFILE_CRUISE, .args = {12, 1.1},
                               .plan_pitch_rad = NAN, .plan_speed_mps = NAN,
                               .unplanned_speed_mps = 1.3};
    gp_pilot pilot;
    gp_pilot_command out;
    gp_pilot_enter(&pilot, &cruise, 0, NAN);
    gp_pilot_step(&pilot, &cruise, 0, NAN, NAN, &out);
    CHECK_NEAR(out.depth_target_m, 12, 0);
    CHECK_NEAR(out.pitch_rad, 0, 0);
    CHECK_NEAR(out.ballast_cc, 0, 0);
    CHECK_NEAR(out.speed_mps, 1.1, 0);
    CHECK_NEAR(out.thrust_w, 0, 0);
    cruise.plan_speed_mps = 0.9;
    gp_pilot_step(&pilot, &cruise, 0, NAN, NAN, &out);
    CHECK_NEAR(out.speed_mps, 0.9, 0);
    /* altitude(8, auto): the speed left out flies the unplanned speed; 8 m above the floor */
    gp_profile_input altitude = {.kind = GP_PROFILE_ALTITUDE, .args = {8},
                                 .plan_pitch_rad = NAN, .plan_speed_mps = NAN,
                                 .unplanned_speed_mps = 1.3};
    gp_pilot_enter(&pilot, &altitude, 20, 15);
    gp_pilot_step(&pilot, &altitude, 20, NAN, 15, &out);
    CHECK_NEAR(out.depth_target_m, 27, 0);
    CHECK_NEAR(out.speed_mps, 1.3, 0);
    gp_pilot_step(&pilot, &altitude, 20, NAN, NAN, &out);  /* no floor in range: deeper */
    CHECK_NEAR(out.depth_target_m, 28, 0);
    gp_pilot_step(&pilot, &altitude, 2, NAN, 5, &out);  /* shallower than 8 m: the surface */
    CHECK_NEAR(out.depth_target_m, 0, 0);
}

void test_a_yo_should_command_its_thrust(void)
{
    gp_profile_input in = yo_input(5, 10);
    in.thrust_w = 4;
    gp_pilot pilot;
    gp_pilot_command out;
    gp_pilot_enter(&pilot, &in, 0, NAN);
    gp_pilot_step(&pilot, &in, 0, NAN, NAN, &out);
    CHECK_NEAR(out.thrust_w, 4, 0);
    CHECK_NEAR(out.speed_mps, 0, 0);
    CHECK(out.pitch_rad < 0);  /* still a glide: the thruster assists it */
}
