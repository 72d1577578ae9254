/* The paper's Fig. 2 (examples/fig2.mission) as a hand-written mission table, the way
 * the code generator emits one. The unit tests and the pty end-to-end test run it.
 *
 *            missiontime >= 500 && < 1500            missiontime >= 2000
 *     +----+ ---------- call --------> +----+   +----+ <------ goto ------- s1
 *     | s1 |                           | s2 |   | s3 | -- missiontime >= 2500 --> exit
 *     +----+ <-- return (>= 1500) ---- +----+   +----+
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

static int s1_goto_s3(const double *s, const double *v) { (void)v; return s[MISSIONTIME] >= 2000; }
static int s1_call_s2(const double *s, const double *v)
{
    (void)v;
    return s[MISSIONTIME] >= 500 && s[MISSIONTIME] < 1500;
}
static int s2_return(const double *s, const double *v) { (void)v; return s[MISSIONTIME] >= 1500; }
static int s3_exit(const double *s, const double *v) { (void)v; return s[MISSIONTIME] >= 2500; }

static void yo_5_10(const double *s, const double *v, double *a)
{
    (void)s; (void)v;
    a[0] = 5.0; a[1] = 10; a[2] = .454; a[3] = .454;
}
static void thermo_5_20(const double *s, const double *v, double *a)
{
    (void)s; (void)v;
    a[0] = 5; a[1] = 20; a[2] = .454; a[3] = .454; a[4] = 10; a[5] = 10;
}
static void yo_5_20(const double *s, const double *v, double *a)
{
    (void)s; (void)v;
    a[0] = 5; a[1] = 20; a[2] = .454; a[3] = .454;
}

static const double s1_point[1][2] = {{3910.5, -7349.8058}};
static const double s3_point[1][2] = {{3910.5, -7349.5058}};
static const gp_profile s1_profiles[] = {{GP_PROFILE_YO, 4, yo_5_10, 0.0}};
static const gp_profile s2_profiles[] = {{GP_PROFILE_THERMOTRACKYO, 6, thermo_5_20, 0.0}};
static const gp_profile s3_profiles[] = {{GP_PROFILE_YO, 4, yo_5_20, 0.0}};
static const uint8_t s1_sensors[] = {GP_SENSOR_MISSIONTIME, GP_SENSOR_DEPTH, GP_SENSOR_PITCH};
static const uint8_t s2_sensors[] = {GP_SENSOR_MISSIONTIME, GP_SENSOR_DEPTH, GP_SENSOR_PITCH,
                                       GP_SENSOR_TEMP};
static const uint8_t s3_sensors[] = {GP_SENSOR_MISSIONTIME, GP_SENSOR_DEPTH, GP_SENSOR_PITCH};
static const gp_event s1_events[] = {
    {s1_goto_s3, NULL, GP_ACT_GOTO, 2},
    {s1_call_s2, NULL, GP_ACT_CALL, 1},
};
static const gp_event s2_events[] = {{s2_return, NULL, GP_ACT_RETURN, 0}};
static const gp_event s3_events[] = {{s3_exit, NULL, GP_ACT_EXIT, 0}};

static const gp_state states[] = {
    {"s1", {GP_ROUTE_NAV, 1, 0.0, s1_point}, s1_profiles, 1, s1_sensors, 3, s1_events, 2, 0, 0,
     0x7, 0},
    {"s2", {GP_ROUTE_NOHEADING, 0, 0.0, NULL}, s2_profiles, 1, s2_sensors, 4, s2_events, 1, 0, 0,
     0x207, 0},
    {"s3", {GP_ROUTE_NAV, 1, 0.0, s3_point}, s3_profiles, 1, s3_sensors, 3, s3_events, 1, 0, 0,
     0x7, 0},
};

/* the TS-7800 and the Slocum G2 shallow glider's pump (+-233 cc) */
static const double clocks_mhz[] = {300.0, 500.0};

const gp_mission gp_mission_table = {
    .name = "sampleMission",
    .hash = "5db9c7f6bccd8ec471713fb8071fb0f3aceb0069b185b69571c5783b1814d1b9",
    .states = states,
    .n_states = 3,
    .var_initial = NULL,
    .n_vars = 0,
    .stack_depth = 8,
    .read_mask = (1u << 0) | (1u << 1) | (1u << 6) | (1u << 7) | (1u << 9),
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
