/* A mission the checker would reject, to show the runtime refuses what the checker
 * missed instead of crashing: `a` and `b` call each other past a stack depth of 2.
 *
 *   a --call (missiontime >= 10)--> b --call (>= 20)--> a --call (next tick)--> b: overflow
 */
#include <stddef.h>

#include <math.h>

#include "gp_mission.h"

#define MISSIONTIME GP_SENSOR_MISSIONTIME

static const char *const sensor_names[GP_N_SENSORS] = {
    "missiontime", "depth", "pitch", "roll", "heading", "altitude", "lat", "lon", "battery",
    "temp", "conductivity", "salinity", "oxygen", "chlorophyll", "backscatter", "current",
    "modem", "halfcycle", "wptdist", "timeofday",
};

static int after_10(const double *s, const double *v) { (void)v; return s[MISSIONTIME] >= 10; }
static int after_20(const double *s, const double *v) { (void)v; return s[MISSIONTIME] >= 20; }
static void hover_5(const double *s, const double *v, double *a) { (void)s; (void)v; a[0] = 5; }

static const gp_profile hover[] = {{GP_PROFILE_HOVER, 1, hover_5, 0.0}};
static const gp_event a_events[] = {{after_10, NULL, GP_ACT_CALL, 1}};
static const gp_event b_events[] = {{after_20, NULL, GP_ACT_CALL, 0}};
static const gp_state states[] = {
    {"a", {GP_ROUTE_NOHEADING, 0, 0.0, NULL}, hover, 1, NULL, 0, a_events, 1, 0, 0, 0, 0},
    {"b", {GP_ROUTE_NOHEADING, 0, 0.0, NULL}, hover, 1, NULL, 0, b_events, 1, 0, 0, 0, 0},
};

/* the TS-7800 and the Slocum G2 shallow glider's pump (+-233 cc) */
static const double clocks_mhz[] = {300.0, 500.0};

const gp_mission gp_mission_table = {
    .name = "stacker",
    .hash = "0000000000000000000000000000000000000000000000000000000000000001",
    .states = states,
    .n_states = 2,
    .stack_depth = 2,
    .read_mask = 1u,
    .default_ballast_cc = 230.0,
    .max_ballast_cc = 233.0,
    .reserve_j = 1.17e6,  /* 15 % of the 7.8 MJ pack Fig. 2 flies without annotations */
    /* the shallow Slocum's envelope (its vehicle file): 100 m, 2 x its 26 deg, its 3 m
     * nominal top, a full stroke of 466 cc at 42.09 cc/s; surface on a breach */
    .envelope = {.max_depth_m = 100.0, .max_pitch_rad = 0.9075712110370514,
                 .min_yo_band_m = 3.0, .min_inflection_s = 11.07,
                 .max_turn_rate_rad_s = INFINITY, .max_pump_power_w = INFINITY,
                 .action = GP_ENVELOPE_SURFACE},
    .clocks_mhz = clocks_mhz,
    .n_clocks = 2,
    .sensor_names = sensor_names,
};
