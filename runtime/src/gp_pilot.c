/* Flight profiles (docs/pilot.md). The thermocline tracker is the part the paper's
 * first sea trial got wrong: the robust one filters and never resets on noise. */
#include "gp_pilot.h"

#include <math.h>
#include <string.h>

#include "gp_frame.h"

static void start_leg(gp_pilot *pilot, uint8_t leg)
{
    pilot->leg = leg;
    pilot->detected = 0;
    pilot->n_window = 0;
    pilot->n_recent = 0;
    pilot->previous_c = NAN;
}

/* The yo's altimeter stop (Slocum's d_target_altitude): whether the altitude reading is
 * at or below the profile's `altitude` argument. An argument left out (0) or <= 0 is no
 * stop; a NaN reading (no floor in the altimeter's range) never stops a dive. */
static int at_altimeter_stop(const gp_profile_input *in, double altitude_m)
{
    double stop = in->args[in->kind == GP_PROFILE_THERMOTRACKYO ? GP_THERMOTRACKYO_ALTITUDE_ARG
                                                                : GP_YO_ALTITUDE_ARG];
    return stop > 0.0 && altitude_m <= stop;
}

void gp_pilot_enter(gp_pilot *pilot, const gp_profile_input *in, double depth_m,
                    double altitude_m)
{
    memset(pilot, 0, sizeof *pilot);
    pilot->lo_m = in->args[0];
    pilot->hi_m = in->args[1];
    pilot->halfcycle = in->kind == GP_PROFILE_YO || in->kind == GP_PROFILE_THERMOTRACKYO;
    int dive = depth_m < in->args[1] && !(pilot->halfcycle && at_altimeter_stop(in, altitude_m));
    start_leg(pilot, dive ? GP_LEG_DIVE : GP_LEG_CLIMB);
}

static double median_of_recent(const gp_pilot *pilot)
{
    const double *r = pilot->recent_c;
    if (pilot->n_recent == 1) {
        return r[0];
    }
    if (pilot->n_recent == 2) {
        return (r[0] + r[1]) / 2.0;
    }
    double a = r[0], b = r[1], c = r[2];
    return fmax(fmin(a, b), fmin(fmax(a, b), c));
}

static void window_append(gp_pilot *pilot, double depth_m, double temp_c)
{
    if (pilot->n_window == GP_TRACK_WINDOW) {
        memmove(pilot->window, pilot->window + 1, (GP_TRACK_WINDOW - 1) * sizeof pilot->window[0]);
        pilot->n_window--;
        pilot->summarized = 0;  /* the oldest may have been an extreme, and indices moved */
    }
    uint8_t at = pilot->n_window++;
    pilot->window[at] = (gp_reading){depth_m, temp_c};
    if (at == 0) {  /* a window of one reading */
        pilot->summarized = 1;
        pilot->warmest = pilot->coldest = 0;
        pilot->shallowest_m = pilot->deepest_m = depth_m;
    } else if (pilot->summarized) {
        pilot->warmest = temp_c > pilot->window[pilot->warmest].temp_c ? at : pilot->warmest;
        pilot->coldest = temp_c < pilot->window[pilot->coldest].temp_c ? at : pilot->coldest;
        pilot->shallowest_m = depth_m < pilot->shallowest_m ? depth_m : pilot->shallowest_m;
        pilot->deepest_m = depth_m > pilot->deepest_m ? depth_m : pilot->deepest_m;
    }
}

/* Keep the readings within `depth_threshold` of `depth_m` and summarize what is kept. */
static void filter_window(gp_pilot *pilot, double depth_m, double depth_threshold)
{
    gp_reading *window = pilot->window;
    int n = pilot->n_window, kept = 0;
    pilot->summarized = 0;
    for (int i = 0; i < n; i++) {
        gp_reading reading = window[i];
        if (!(fabs(reading.depth_m - depth_m) <= depth_threshold)) {
            continue;
        }
        if (kept == 0 || reading.temp_c > window[pilot->warmest].temp_c) {
            pilot->warmest = (uint8_t)kept;
        }
        if (kept == 0 || reading.temp_c < window[pilot->coldest].temp_c) {
            pilot->coldest = (uint8_t)kept;
        }
        if (kept == 0 || reading.depth_m < pilot->shallowest_m) {
            pilot->shallowest_m = reading.depth_m;
        }
        if (kept == 0 || reading.depth_m > pilot->deepest_m) {
            pilot->deepest_m = reading.depth_m;
        }
        window[kept++] = reading;
    }
    pilot->n_window = (uint8_t)kept;
    pilot->summarized = kept > 0;
}

/* Robust: median-filtered temperature; window keeps readings near the current depth.
 * Every reading is kept when the shallowest and the deepest are (a difference rounds
 * monotonically): then the summary holds as it is, and the window is not walked; most
 * ticks of a leg are such ticks.
 * @return index of the reading `a` that detects the thermocline, or -1 */
static int robust_detect(gp_pilot *pilot, double depth_m, double *temp_c,
                         double temp_threshold, double depth_threshold)
{
    if (pilot->n_recent == 3) {
        pilot->recent_c[0] = pilot->recent_c[1];
        pilot->recent_c[1] = pilot->recent_c[2];
        pilot->n_recent = 2;
    }
    pilot->recent_c[pilot->n_recent++] = *temp_c;
    *temp_c = median_of_recent(pilot);
    if (!(pilot->summarized && fabs(pilot->shallowest_m - depth_m) <= depth_threshold
          && fabs(pilot->deepest_m - depth_m) <= depth_threshold)) {
        filter_window(pilot, depth_m, depth_threshold);
    }
    if (pilot->n_window == 0) {
        return -1;
    }
    double warm_diff = fabs(pilot->window[pilot->warmest].temp_c - *temp_c);
    double cold_diff = fabs(pilot->window[pilot->coldest].temp_c - *temp_c);
    int a = cold_diff > warm_diff ? pilot->coldest : pilot->warmest;
    return fmax(warm_diff, cold_diff) >= temp_threshold ? a : -1;
}

/* Naive: raw readings; any reading against the leg's direction empties the window. */
static int naive_detect(gp_pilot *pilot, double depth_m, double temp_c,
                        double temp_threshold, double depth_threshold)
{
    double previous = pilot->previous_c;
    pilot->previous_c = temp_c;
    if (!isnan(previous)
        && ((pilot->leg == GP_LEG_DIVE && temp_c > previous)
            || (pilot->leg == GP_LEG_CLIMB && temp_c < previous))) {
        pilot->n_window = 0;
    }
    for (int i = 0; i < pilot->n_window; i++) {
        if (fabs(pilot->window[i].temp_c - temp_c) >= temp_threshold
            && fabs(pilot->window[i].depth_m - depth_m) <= depth_threshold) {
            return i;
        }
    }
    return -1;
}

static int track_thermocline(gp_pilot *pilot, const gp_profile_input *in, double depth_m,
                             double temp_c)
{
    double min_m = in->args[0], max_m = in->args[1];
    double temp_threshold = in->args[4], depth_threshold = in->args[5];
    if (!isfinite(depth_m) || !isfinite(temp_c)) {
        return 0;  /* no reading this tick: nothing to learn from */
    }
    int a = in->naive ? naive_detect(pilot, depth_m, temp_c, temp_threshold, depth_threshold)
                      : robust_detect(pilot, depth_m, &temp_c, temp_threshold, depth_threshold);
    if (a < 0) {
        window_append(pilot, depth_m, temp_c);
        return 0;
    }
    double z = (pilot->window[a].depth_m + depth_m) / 2.0;
    /* max(min, lo) and min(max, hi) that keep a NaN bound (fmax and fmin would put a
     * number the mission never gave in its place: docs/pilot.md) */
    double lo = z - depth_threshold / 2.0, hi = z + depth_threshold / 2.0;
    pilot->lo_m = lo > min_m ? lo : min_m;
    pilot->hi_m = hi < max_m ? hi : max_m;
    pilot->n_window = 0;
    pilot->detected = 1;
    return GP_PILOT_DETECTED;
}

static int fly_yo(gp_pilot *pilot, const gp_profile_input *in, double depth_m, double temp_c,
                  double altitude_m, gp_pilot_command *out)
{
    int tracking = in->kind == GP_PROFILE_THERMOTRACKYO;
    int changed = 0;
    if (!tracking) {
        pilot->lo_m = in->args[0];
        pilot->hi_m = in->args[1];
    }
    uint8_t leg = pilot->leg;
    if (leg == GP_LEG_DIVE && (depth_m >= pilot->hi_m || at_altimeter_stop(in, altitude_m))) {
        leg = GP_LEG_CLIMB;
    } else if (leg == GP_LEG_CLIMB && depth_m <= pilot->lo_m) {
        leg = GP_LEG_DIVE;
    }
    if (leg != pilot->leg) {
        if (tracking && !pilot->detected) {  /* thermocline lost: search the whole range */
            pilot->lo_m = in->args[0];
            pilot->hi_m = in->args[1];
        }
        start_leg(pilot, leg);
        if (pilot->halfcycle < UINT32_MAX) {
            pilot->halfcycle++;
        }
        changed |= GP_PILOT_TURNED;
    }
    if (tracking) {
        changed |= track_thermocline(pilot, in, depth_m, temp_c);
    }
    int climbing = pilot->leg == GP_LEG_CLIMB;
    double pitch = isnan(in->plan_pitch_rad) ? in->args[climbing ? 3 : 2] : in->plan_pitch_rad;
    out->depth_target_m = climbing ? pilot->lo_m : pilot->hi_m;
    out->pitch_rad = climbing ? pitch : -pitch;
    out->ballast_cc = climbing ? in->ballast_cc : -in->ballast_cc;
    out->flags = climbing ? GP_FLAG_CLIMBING : 0;
    out->speed_mps = 0.0;
    out->thrust_w = in->thrust_w;
    return changed;
}

/* A propelled profile's speed: the plan's; without a plan the speed argument, or the
 * mission's unplanned speed where it is `auto` (left out: 0) or not positive. */
static double propelled_speed(const gp_profile_input *in)
{
    if (!isnan(in->plan_speed_mps)) {
        return in->plan_speed_mps;
    }
    return in->args[1] > 0.0 ? in->args[1] : in->unplanned_speed_mps;
}

/* altitude(height, speed): the depth at which the altimeter would read `height`; with no
 * floor in the altimeter's range (NaN) the floor lies deeper: down by `height`. */
static double altitude_target_m(double height_m, double depth_m, double altitude_m)
{
    double target = isnan(altitude_m) ? depth_m + height_m : depth_m + altitude_m - height_m;
    return target > 0.0 ? target : 0.0;  /* a NaN depth too: the surface */
}

int gp_pilot_step(gp_pilot *pilot, const gp_profile_input *in, double depth_m, double temp_c,
                  double altitude_m, gp_pilot_command *out)
{
    switch (in->kind) {
    case GP_PROFILE_YO:
    case GP_PROFILE_THERMOTRACKYO:
        return fly_yo(pilot, in, depth_m, temp_c, altitude_m, out);
    case GP_PROFILE_SURFACE:
        *out = (gp_pilot_command){0.0, GP_SURFACE_PITCH_RAD, in->ballast_cc,
                                  GP_FLAG_SURFACE | GP_FLAG_CLIMBING, 0.0, 0.0};
        return 0;
    case GP_PROFILE_CRUISE:
        *out = (gp_pilot_command){in->args[0], 0.0, 0.0, 0, propelled_speed(in), 0.0};
        return 0;
    case GP_PROFILE_ALTITUDE:
        *out = (gp_pilot_command){altitude_target_m(in->args[0], depth_m, altitude_m), 0.0,
                                  0.0, 0, propelled_speed(in), 0.0};
        return 0;
    default:  /* hover */
        *out = (gp_pilot_command){in->args[0], 0.0, 0.0, 0, 0.0, 0.0};
        return 0;
    }
}
