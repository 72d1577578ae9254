/* The simulated flight in C: the glider, its science computer and its battery flown
 * tick after tick with the runtime's own step (step.c), each tick as sim/loop.py's
 * `simulate` flies it with the Python models (sim/vehicle.py, sim/science.py,
 * sim/ocean.py, sim/energy.py): the same operations on the same doubles in the same
 * order, through the same C library (built with -ffp-contract=off and sin and cos called
 * as written), so that the flights are the same bit for bit
 * (tests/test_sim_differential.py).
 * What only Python computes comes from the caller: blocks of random numbers from the
 * run's generators, the glide speeds at a pitch (the angle of attack solved by
 * power_models/flight.py). No allocation: the caller gives the context and the columns. */
#include <math.h>
#include <string.h>

#include "step.h"


#define GPS_PI 3.14159265358979323846
#define GPS_RAD (GPS_PI / 180.0)
#define GPS_NO_STATE GP_NO_STATE
#define GPS_NOISE_BLOCK 4096  /* science.py's _NOISE_BLOCK: rows drawn per block */
#define GPS_PITCHES 256       /* glide speeds kept per pitch: recomputed when evicted */
#define GPS_WAVES 8
#define GPS_DEVICES 8
#define GPS_TRACE 1024        /* transitions held before the caller must take them */
#define GPS_GAUGE_TICKS 64    /* energy.py's GAUGE_TICKS: the coulomb counter's read-out */

/* segments.py's phases */
enum { GPS_GLIDE, GPS_SURFACE, GPS_IRIDIUM, GPS_PUMP, GPS_PITCH_PHASE };

/* Why gps_fly returned. */
enum {
    GPS_RAN = 0,          /**< flew the ticks asked for */
    GPS_ENDED = 1,        /**< the mission exited (or the energy guard ended it) */
    GPS_FAULT = 2,        /**< the runtime refused an event (gps_flight.step.report) */
    GPS_NEED_NOISE = 3,   /**< a block of random numbers is used up: give the next */
    GPS_NEED_PITCH = 4,   /**< no glide speeds for `need_pitch_rad`: give them */
    GPS_TRACE_FULL = 5,   /**< take the transitions */
    GPS_DONE = 6,         /**< the run's last tick is flown */
    GPS_ENVELOPE = 7,     /**< the envelope guard held a command: take its words */
    GPS_SURFACED = 8,     /**< surfaced since the last tick (gps_flight_stop_at_surfacings):
                               the shore's turn before the next tick (gps_flight_surfaced) */
};

/** The vehicle, the water and the battery: constant over a run (sim/vehicle.py,
 *  sim/science.py, sim/ocean.py, sim/energy.py). Units as their names say. */
typedef struct {
    double tick_s;
    /* the glider */
    double pump_rate_cc_s, climb_pitch_error_rad, dive_pitch_error_rad;
    double bottom_turn_s, top_turn_s, surface_s, iridium_s;
    double rho_kg_m3, g_m_s2, hull_volume_cc, compressibility_per_pa, trim_cc;
    double surface_depth_m, hover_rate_m_s, pitch_rate_rad_s, min_pumped_cc, earth_radius_m;
    double current_north_mps, current_east_mps;
    double correction_speed_mps;  /* the current correction's speed through the water, 0: off */
    const double *lift_cc;    /* the water's buoyancy every lift_step_m from the surface */
    int32_t n_lift;           /* 0: uniform water */
    double lift_step_m;
    /* the sea floor along time: n_floor samples, 0 none */
    const double *floor_times_s, *floor_depths_m;
    int32_t n_floor;
    /* the water: a thermocline (ocean.Thermocline, n_depths 0) or measured casts
     * (ocean.MeasuredProfile: n_casts casts of n_depths depths, row-major) */
    double surface_c, deep_c, thermocline_m, thickness_m, surface_psu, deep_psu;
    int32_t n_waves;
    double wave_amplitude_m[GPS_WAVES], wave_period_s[GPS_WAVES], wave_phase_rad[GPS_WAVES];
    const double *depths_m, *casts_s, *temperatures_c, *salinities_psu;
    int32_t n_depths, n_casts;
    /* the science computer */
    double temperature_sigma_c, depth_sigma_m, spike_c, lag_keep, start_epoch_s;
    int32_t spikes;           /* a stream of spikes is drawn */
    double constant[GP_N_SENSORS];  /* readings the glider holds (NaN: none) */
    uint32_t sent_always;     /* sensors without a device */
    uint32_t device_bits[GPS_DEVICES];
    int32_t n_devices;
    /* the battery's bill */
    double gliding_w, surface_w, iridium_w, pitch_energy_j;
    double pump_out_j_per_cc, pump_out_j_per_cc_m, pump_in_j_per_cc, pump_in_j_per_cc_m;
    double computer_w[GP_MAX_STATES], boot_j;
    int32_t computer_billed;  /* 0: the hotel load holds the computer */
    double device_on_w[GPS_DEVICES], device_warmup_j[GPS_DEVICES];
    double battery_j;
    int32_t last_tick;
} gps_physics;

/** The columns of the run, one row per tick (sim/loop.py COLUMN_TYPES). */
typedef struct {
    double *depth_m, *pitch_rad, *temperature_c, *temp_reading_c;
    int16_t *state;
    int8_t *stack_depth, *profile;
    int32_t *sensor_power;
    int8_t *phase;
    double *pumped_out_cc, *pumped_in_cc;
    uint8_t *inflection;
    double *lat_deg, *lon_deg;
    double *propulsion_w;     /* 0: the C loop flies gliders without a thruster */
} gps_columns;

typedef struct {
    uint32_t tick;
    uint8_t kind, from, to, depth;
} gps_transition;

/** A flight in progress. */
typedef struct {
    gps_step step;
    const gps_physics *p;
    gps_columns columns;
    int32_t tick;                       /* the next tick to fly */
    uint8_t ended;                      /* GPS_ENDED or GPS_FAULT once over */
    /* the glider */
    double depth_m, pitch_rad, ballast_cc, heading_rad, lat_deg, lon_deg, dr_lat_deg,
        dr_lon_deg, surface_time_s, turning_to, turn_left_s, floor_m;
    double measured_north_mps, measured_east_mps;  /* the current dead reckoning flies with */
    int32_t ticks_since_fix;
    int32_t surfacings, grounded_ticks;
    int32_t surfacings_seen;            /* by the caller, when it stops at surfacings */
    uint8_t stops_at_surfacings;
    double first_grounded_s;
    int8_t phase;
    uint8_t inflection, grounded;
    double pumped_out_cc, pumped_in_cc;
    /* glide speeds per square root of a cc at each pitch met */
    double pitch_key[GPS_PITCHES], u_per_root[GPS_PITCHES], w_per_root[GPS_PITCHES];
    int32_t n_pitches, next_pitch;
    double need_pitch_rad;
    /* the science computer */
    const double *normal;               /* rows of (temperature, depth) standard normals */
    const double *spike_signs;
    int32_t normal_at, spike_at;        /* row taken next; GPS_NOISE_BLOCK: used up */
    double ctd_c, flicker_c;
    uint32_t sensor_power;
    /* the coulomb counter */
    double left_j, block_j[GPS_GAUGE_TICKS];
    int32_t counted;
    uint8_t device_was_on[GPS_DEVICES];
    /* the tick in progress: its COMMAND waits for the glide speeds it needs */
    gp_command command;
    gp_tick_report report;
    uint8_t pending;
    /* transitions not yet taken */
    gps_transition trace[GPS_TRACE];
    int32_t n_trace;
} gps_flight;

size_t gps_flight_size(void)
{
    return sizeof(gps_flight);
}

size_t gps_physics_size(void)
{
    return sizeof(gps_physics);
}

/* ---- the water ------------------------------------------------------------------- */

/* ocean._interp_scalar: np.interp for one value, the operations in the same order */
static double interp(const double *xs, const double *ys, int n, double x)
{
    int i = 0;  /* bisect_right: the first index whose x is above */
    int hi = n;
    while (i < hi) {
        int mid = (i + hi) / 2;
        if (x < xs[mid]) {
            hi = mid;
        } else {
            i = mid + 1;
        }
    }
    if (i == 0) {
        return ys[0];
    }
    if (i == n) {
        return ys[n - 1];
    }
    double x0 = xs[i - 1], x1 = xs[i];
    return ys[i - 1] + (ys[i] - ys[i - 1]) * (x - x0) / (x1 - x0);
}

/* MeasuredProfile._interpolate on floats */
static double measured(const gps_physics *p, const double *table, double depth_m, double time_s)
{
    int n = p->n_depths;
    if (p->n_casts == 1) {
        return interp(p->depths_m, table, n, depth_m);
    }
    int k = 0;  /* bisect_left, less one, within 0..n_casts - 2 */
    int hi = p->n_casts;
    while (k < hi) {
        int mid = (k + hi) / 2;
        if (p->casts_s[mid] < time_s) {
            k = mid + 1;
        } else {
            hi = mid;
        }
    }
    k = k - 1 < 0 ? 0 : k - 1;
    k = k > p->n_casts - 2 ? p->n_casts - 2 : k;
    double t0 = p->casts_s[k], t1 = p->casts_s[k + 1];
    double w = (time_s - t0) / (t1 - t0);
    w = 0.0 > w ? 0.0 : w;  /* min(max(w, 0.0), 1.0) as Python's max and min pick */
    w = 1.0 < w ? 1.0 : w;
    double a = interp(p->depths_m, table + (size_t)k * (size_t)n, n, depth_m);
    double b = interp(p->depths_m, table + (size_t)(k + 1) * (size_t)n, n, depth_m);
    return a * (1.0 - w) + b * w;
}

/* ocean.Thermocline._water / MeasuredProfile.water_at: temperature and salinity */
static void water_at(const gps_physics *p, double depth_m, double time_s, double *temp_c,
                     double *salinity_psu)
{
    if (p->n_depths > 0) {
        *temp_c = measured(p, p->temperatures_c, depth_m, time_s);
        *salinity_psu = measured(p, p->salinities_psu, depth_m, time_s);
        return;
    }
    double centre = p->thermocline_m;
    for (int i = 0; i < p->n_waves; i++) {
        centre = centre + p->wave_amplitude_m[i]
                              * sin(2.0 * GPS_PI * time_s / p->wave_period_s[i]
                                    + p->wave_phase_rad[i]);
    }
    double thickness = 1e-6 > p->thickness_m ? 1e-6 : p->thickness_m;
    double warm = 0.5 * (1.0 - tanh((depth_m - centre) / (thickness / 4.0)));
    *temp_c = p->deep_c + (p->surface_c - p->deep_c) * warm;
    *salinity_psu = p->deep_psu + (p->surface_psu - p->deep_psu) * warm;
}

/* vehicle.Stratification.at */
static double lift_at(const gps_physics *p, double depth_m)
{
    double x = depth_m / p->lift_step_m;
    int last = p->n_lift - 1;
    if (!(x < (double)last)) {
        return p->lift_cc[last];
    }
    if (x <= 0.0) {
        return p->lift_cc[0];
    }
    int i = (int)x;
    return p->lift_cc[i] + (p->lift_cc[i + 1] - p->lift_cc[i]) * (x - (double)i);
}

/* ---- the glider (sim/vehicle.py, GliderSim) -------------------------------------- */

static double py_min(double a, double b)  /* Python's min(a, b) */
{
    return b < a ? b : a;
}

/* geo.move_degrees */
static void move_degrees(const gps_physics *p, double *lat, double *lon, double north_m,
                         double east_m)
{
    double lat0 = *lat;
    *lat = lat0 + north_m / (p->earth_radius_m * GPS_RAD);
    *lon = *lon + east_m / (p->earth_radius_m * cos(lat0 * GPS_RAD) * GPS_RAD);
}

/* geo.degrees_to_ddmm */
static double degrees_to_ddmm(double x)
{
    double a = fabs(x);
    double whole = floor(a);
    return copysign(whole * 100.0 + (a - whole) * 60.0, x);
}

/* geo.offset_m: (north, east) [m] from point 1 to point 2, the operations in its order */
static void offset_m(const gps_physics *p, double lat1, double lon1, double lat2, double lon2,
                     double *north_m, double *east_m)
{
    double scale = p->earth_radius_m * GPS_PI / 180.0;
    *north_m = (lat2 - lat1) * scale;
    *east_m = (lon2 - lon1) * scale * cos(lat1 * GPS_PI / 180.0);
}

/* navigation.corrected_heading */
static double corrected_heading(double course_rad, double speed_mps, double north_mps,
                                double east_mps)
{
    if (!(speed_mps > 0.0)) {
        return course_rad;
    }
    double across = east_mps * cos(course_rad) - north_mps * sin(course_rad);
    double ratio = -across / speed_mps;
    ratio = ratio > 1.0 ? 1.0 : ratio < -1.0 ? -1.0 : ratio;
    double heading = course_rad + asin(ratio);
    if (heading < 0.0) {
        heading += 2.0 * GPS_PI;
    } else if (heading >= 2.0 * GPS_PI) {
        heading -= 2.0 * GPS_PI;
    }
    return heading;
}

/* GliderSim.flows */
static int flows(const gps_flight *f)
{
    const gps_physics *p = f->p;
    return p->current_north_mps != 0.0 || p->current_east_mps != 0.0
           || f->measured_north_mps != 0.0 || f->measured_east_mps != 0.0;
}

/* GliderSim._drift: the estimate with the current measured, the true position with the
 * water's */
static void drift(gps_flight *f, double distance_m, double dt)
{
    const gps_physics *p = f->p;
    double north = distance_m * cos(f->heading_rad);
    double east = distance_m * sin(f->heading_rad);
    double dr_north = north + f->measured_north_mps * dt;
    double dr_east = east + f->measured_east_mps * dt;
    if (dr_north != 0.0 || dr_east != 0.0) {
        move_degrees(p, &f->dr_lat_deg, &f->dr_lon_deg, dr_north, dr_east);
    }
    f->ticks_since_fix++;
    if (!flows(f)) {
        f->lat_deg = f->dr_lat_deg;
        f->lon_deg = f->dr_lon_deg;
        return;
    }
    north += p->current_north_mps * dt;
    east += p->current_east_mps * dt;
    move_degrees(p, &f->lat_deg, &f->lon_deg, north, east);
}

/* GliderSim._fix: the measured current corrected by the fix (navigation.updated_current),
 * the estimate set to it */
static void fix(gps_flight *f)
{
    double north, east;
    offset_m(f->p, f->dr_lat_deg, f->dr_lon_deg, f->lat_deg, f->lon_deg, &north, &east);
    double since_s = (double)f->ticks_since_fix * f->p->tick_s;
    if (since_s > 0.0) {
        f->measured_north_mps = f->measured_north_mps + north / since_s;
        f->measured_east_mps = f->measured_east_mps + east / since_s;
    }
    f->ticks_since_fix = 0;
    f->dr_lat_deg = f->lat_deg;
    f->dr_lon_deg = f->lon_deg;
}

/* GliderSim._at_surface */
static void at_surface(gps_flight *f, double dt)
{
    const gps_physics *p = f->p;
    f->depth_m = 0.0;
    if (f->surface_time_s < 0.0) {
        f->surface_time_s = 0.0;
        f->surfacings++;
    }
    double elapsed = f->surface_time_s;
    f->surface_time_s += dt;
    if (elapsed < p->surface_s && p->surface_s <= f->surface_time_s) {
        fix(f);  /* the GPS fix */
    }
    int in_call = p->surface_s <= elapsed && elapsed < p->surface_s + p->iridium_s;
    f->phase = in_call ? GPS_IRIDIUM : GPS_SURFACE;
    drift(f, 0.0, dt);
}

/* GliderSim._actuate: returns the time left to glide [s]; *servo_pitch the pitch the
 * servo settles at for the command */
static double actuate(gps_flight *f, double pitch_rad, double ballast_cc, double *servo_pitch)
{
    const gps_physics *p = f->p;
    double dt = p->tick_s;
    if (pitch_rad != 0.0) {
        double error = pitch_rad > 0.0 ? p->climb_pitch_error_rad : p->dive_pitch_error_rad;
        pitch_rad = copysign(fabs(pitch_rad) + error, pitch_rad);
    }
    double dp = pitch_rad - f->pitch_rad;
    double max_dp = p->pitch_rate_rad_s * dt;
    f->pitch_rad = fabs(dp) <= max_dp ? pitch_rad : f->pitch_rad + copysign(max_dp, dp);
    double glide_s = dt;
    double dv = ballast_cc - f->ballast_cc;
    if (dv != 0.0) {
        double moved = py_min(fabs(dv), p->pump_rate_cc_s * dt);
        if (dv > 0.0) {
            f->pumped_out_cc = moved;
        } else {
            f->pumped_in_cc = moved;
        }
        f->ballast_cc = moved == fabs(dv) ? ballast_cc : f->ballast_cc + copysign(moved, dv);
        glide_s = dt - moved / p->pump_rate_cc_s;
        double going = copysign(1.0, dv);
        if (fabs(dv) >= p->min_pumped_cc && going != f->turning_to) {
            f->turning_to = going;
            f->inflection = 1;
            f->turn_left_s = going > 0.0 ? p->bottom_turn_s : p->top_turn_s;
        }
    }
    f->phase = glide_s < dt ? GPS_PUMP : GPS_GLIDE;
    if (f->turn_left_s > 0.0 && f->ballast_cc == ballast_cc) {
        double turning = py_min(f->turn_left_s, glide_s);
        f->turn_left_s -= turning;
        glide_s -= turning;
    }
    *servo_pitch = pitch_rad;
    return glide_s;
}

/* GliderSim._per_root: the index of the pitch's speeds, -1 if not known yet (0 speeds
 * outside 0 < pitch < pi/2: index -2) */
static int per_root(const gps_flight *f, double pitch_rad)
{
    if (pitch_rad <= 0.0 || pitch_rad >= GPS_PI / 2) {
        return -2;
    }
    for (int i = 0; i < f->n_pitches; i++) {
        if (f->pitch_key[i] == pitch_rad) {
            return i;
        }
    }
    return -1;
}

/* Whether a tick under this command glides at a pitch whose speeds are not known yet
 * (then need_pitch_rad says which): decided before anything moves, as glider_step will
 * decide it (at the surface, or hovering: no glide). */
static int speeds_missing(gps_flight *f, double pitch_rad, double ballast_cc, int surface)
{
    const gps_physics *p = f->p;
    if (surface && f->depth_m <= p->surface_depth_m) {
        return 0;
    }
    if (ballast_cc == 0.0) {  /* hovering if the pump reaches neutral this tick */
        double dv = -f->ballast_cc;
        if (dv == 0.0 || py_min(fabs(dv), p->pump_rate_cc_s * p->tick_s) == fabs(dv)) {
            return 0;
        }
    }
    if (pitch_rad != 0.0) {
        double error = pitch_rad > 0.0 ? p->climb_pitch_error_rad : p->dive_pitch_error_rad;
        pitch_rad = copysign(fabs(pitch_rad) + error, pitch_rad);
    }
    if (per_root(f, fabs(pitch_rad)) == -1) {
        f->need_pitch_rad = fabs(pitch_rad);
        return 1;
    }
    return 0;
}

/* GliderSim.glide_rates */
static void glide_rates(const gps_flight *f, int speeds, double ballast_cc, double glide_s,
                        double depth_m, double *dz_m, double *distance_m)
{
    const gps_physics *p = f->p;
    double pressure_pa = p->rho_kg_m3 * p->g_m_s2 * depth_m;
    double squeeze_cc = p->hull_volume_cc * p->compressibility_per_pa * pressure_pa;
    double net = ballast_cc + p->trim_cc - squeeze_cc;
    if (p->n_lift > 0) {
        net = net + lift_at(p, depth_m);
    }
    double x = copysign(1.0, ballast_cc) * net;
    double root = sqrt(0.0 > x ? 0.0 : x);
    double u = speeds >= 0 ? f->u_per_root[speeds] * root : 0.0 * root;
    double w = speeds >= 0 ? f->w_per_root[speeds] * root : 0.0 * root;
    *dz_m = (ballast_cc > 0.0 ? -w : w) * glide_s;
    *distance_m = u * glide_s;
}

/* GliderSim.step */
static void glider_step(gps_flight *f, double target_m, double pitch_rad, double ballast_cc,
                        double heading_rad, int heading_valid, int corrects, int surface)
{
    const gps_physics *p = f->p;
    f->pumped_out_cc = f->pumped_in_cc = 0.0;
    f->inflection = f->grounded = 0;
    if (heading_valid) {  /* upstream of it with current correction, unless held as it is */
        f->heading_rad = p->correction_speed_mps == 0.0 || !corrects
                             ? heading_rad
                             : corrected_heading(heading_rad, p->correction_speed_mps,
                                                 f->measured_north_mps, f->measured_east_mps);
    }
    if (surface && f->depth_m <= p->surface_depth_m) {
        at_surface(f, p->tick_s);
        return;
    }
    f->surface_time_s = -1.0;
    double servo_pitch;
    double glide_s = actuate(f, pitch_rad, ballast_cc, &servo_pitch);
    double dz, distance, depth;
    if (ballast_cc == 0.0 && f->ballast_cc == 0.0) {  /* hovering */
        double step_m = py_min(fabs(target_m - f->depth_m), p->hover_rate_m_s * p->tick_s);
        dz = copysign(step_m, target_m - f->depth_m);
        distance = 0.0;
        depth = f->depth_m + dz;
    } else {
        glide_rates(f, per_root(f, fabs(servo_pitch)), f->ballast_cc, glide_s, f->depth_m, &dz,
                    &distance);
        depth = 0.0 < f->depth_m + dz ? f->depth_m + dz : 0.0;  /* max(0.0, d) */
    }
    if (depth > f->floor_m) {  /* the sea floor stops it */
        depth = f->floor_m;
        f->grounded = 1;
    }
    f->depth_m = depth;
    drift(f, distance, p->tick_s);
}

/* ---- the science computer (sim/science.py, ScienceComputer) ---------------------- */

/* `readings`: the sensor array at `tick` (values), the sensors sent (mask), and what the
 * record keeps of it (the water's temperature, the CTD's reading or NaN when it is off) */
static void sense(gps_flight *f, int32_t tick, double *values, uint32_t *mask, double *water_c,
                  double *reading_c)
{
    const gps_physics *p = f->p;
    double time_s = (double)tick * p->tick_s;
    double altitude = NAN;
    if (p->n_floor > 0) {
        double floor = interp(p->floor_times_s, p->floor_depths_m, p->n_floor, time_s);
        f->floor_m = floor == floor ? floor : INFINITY;  /* NaN: no floor there */
        altitude = floor - f->depth_m;
    }
    const double *z = f->normal + 2 * f->normal_at++;
    double temp, salinity;
    water_at(p, f->depth_m, time_s, &temp, &salinity);
    double ctd = f->ctd_c;
    ctd = ctd != ctd ? temp : temp + (ctd - temp) * p->lag_keep;
    f->ctd_c = ctd;
    f->flicker_c = -f->flicker_c;
    double measured = ctd + p->temperature_sigma_c * z[0] + f->flicker_c;
    if (p->spikes) {
        measured += p->spike_c * f->spike_signs[f->spike_at++];
    }
    double depth = f->depth_m + p->depth_sigma_m * z[1];
    for (int i = 0; i < GP_N_SENSORS; i++) {
        values[i] = p->constant[i];
    }
    values[GP_SENSOR_MISSIONTIME] = time_s;
    values[GP_SENSOR_DEPTH] = depth > 0.0 ? depth : 0.0;  /* max(0.0, depth) */
    values[GP_SENSOR_PITCH] = f->pitch_rad;
    values[GP_SENSOR_HEADING] = f->heading_rad;
    values[GP_SENSOR_ALTITUDE] = altitude;
    values[GP_SENSOR_LAT] = degrees_to_ddmm(f->dr_lat_deg);
    values[GP_SENSOR_LON] = degrees_to_ddmm(f->dr_lon_deg);
    values[GP_SENSOR_TEMP] = measured;
    values[GP_SENSOR_CONDUCTIVITY] = 4.29 * (1.0 + 0.021 * (measured - 15.0)) * (salinity / 35.0);
    values[GP_SENSOR_SALINITY] = salinity;
    values[GP_SENSOR_TIMEOFDAY] = fmod(p->start_epoch_s + time_s, 86400.0);
    values[GP_SENSOR_ENERGY_LEFT] = f->left_j;
    uint32_t sent = p->sent_always;
    for (int d = 0; d < p->n_devices; d++) {
        if (f->sensor_power & p->device_bits[d]) {
            sent |= p->device_bits[d];
        }
    }
    *mask = sent;
    *water_c = temp;
    *reading_c = sent >> GP_SENSOR_TEMP & 1u ? measured : NAN;
}

/* ---- the battery (sim/energy.py, Billing and BatteryGauge) ----------------------- */

/* Billing.per_tick_j of the row just recorded: its components summed in their order */
static double bill(gps_flight *f, int32_t row)
{
    const gps_physics *p = f->p;
    const gps_columns *c = &f->columns;
    double dt = p->tick_s;
    int state = c->state[row];
    int phase = c->phase[row];
    uint32_t power = (uint32_t)c->sensor_power[row];
    double depth = c->depth_m[row];
    int idle = state < 0 || state >= f->step.mission->n_states;
    int gliding = phase == GPS_GLIDE || phase == GPS_PUMP || phase == GPS_PITCH_PHASE;
    double total = gliding ? p->gliding_w * dt : 0.0;
    total = total + (phase == GPS_SURFACE ? p->surface_w * dt : 0.0);
    total = total + (phase == GPS_IRIDIUM ? p->iridium_w * dt : 0.0);
    double pump_in = p->pump_in_j_per_cc + p->pump_in_j_per_cc_m * depth;
    total = total + ((p->pump_out_j_per_cc + p->pump_out_j_per_cc_m * depth) * c->pumped_out_cc[row]
                     + (0.0 > pump_in ? 0.0 : pump_in) * c->pumped_in_cc[row]);
    total = total + (c->inflection[row] ? p->pitch_energy_j : 0.0);
    int billed_state = state < f->step.mission->n_states ? state : f->step.mission->n_states - 1;
    double computer = p->computer_w[billed_state] * dt;
    if (row == 0) {
        computer += p->boot_j;
    }
    total = total + (p->computer_billed ? computer : 0.0 * computer);
    for (int d = 0; d < p->n_devices; d++) {
        int on = (power & p->device_bits[d]) != 0;
        int switched_on = on && !f->device_was_on[d];
        f->device_was_on[d] = (uint8_t)on;
        total = total + ((on ? p->device_on_w[d] * dt : 0.0)
                         + (switched_on ? p->device_warmup_j[d] : 0.0));
    }
    return idle ? 0.0 : total;
}

/* numpy's sum of a block of 64 (its pairwise summation: eight running sums) */
static double block_sum(const double *a)
{
    double r[8];
    for (int j = 0; j < 8; j++) {
        r[j] = a[j];
    }
    for (int i = 8; i < GPS_GAUGE_TICKS; i += 8) {
        for (int j = 0; j < 8; j++) {
            r[j] += a[i + j];
        }
    }
    return ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]));
}

/* BatteryGauge.reading: brought up to date every GPS_GAUGE_TICKS ticks */
static double gauge(gps_flight *f, int32_t tick)
{
    int32_t update = tick - tick % GPS_GAUGE_TICKS;
    if (update > f->counted) {
        f->left_j -= block_sum(f->block_j);
        f->counted = update;
    }
    return f->left_j;
}

/* ---- the loop (sim/loop.py, simulate) -------------------------------------------- */

/**
 * @brief A flight before its first tick: the runtime `step` (gps_step_init), the glider
 *        and science computer as the caller set them up (sim/cflight.py), the columns to
 *        fill (p->last_tick + 1 rows each).
 */
void gps_flight_start(gps_flight *f, const gps_physics *p, const gps_columns *columns)
{
    f->p = p;
    f->columns = *columns;
    f->tick = 0;
    f->ended = 0;
    f->counted = 0;
    f->left_j = p->battery_j;
    f->normal_at = f->spike_at = GPS_NOISE_BLOCK;
    f->floor_m = INFINITY;
    f->first_grounded_s = NAN;
    f->n_trace = 0;
    f->pending = 0;
    f->n_pitches = f->next_pitch = 0;
    f->stops_at_surfacings = 0;
    memset(f->device_was_on, 0, sizeof f->device_was_on);
}

/** @brief Keep the glide speeds [m s-1 per square root of a cc] at a pitch [rad]. */
void gps_flight_speeds(gps_flight *f, double pitch_rad, double u_per_root, double w_per_root)
{
    int i = f->n_pitches < GPS_PITCHES ? f->n_pitches++ : f->next_pitch++ % GPS_PITCHES;
    f->pitch_key[i] = pitch_rad;
    f->u_per_root[i] = u_per_root;
    f->w_per_root[i] = w_per_root;
}

/** @brief The next blocks of random numbers: GPS_NOISE_BLOCK rows of two standard
 *         normals (NULL: keep the current), and of spike signs (NULL: keep). */
void gps_flight_noise(gps_flight *f, const double *normal, const double *spike_signs)
{
    if (normal) {
        f->normal = normal;
        f->normal_at = 0;
    }
    if (spike_signs) {
        f->spike_signs = spike_signs;
        f->spike_at = 0;
    }
}

static void note(gps_flight *f, uint32_t tick, const gp_transition *t)
{
    f->trace[f->n_trace++] = (gps_transition){tick, t->kind, t->from, t->to, t->depth};
}

/* The rest of a tick's row: its COMMAND's outputs (or, refused, the state it was in). */
static void record_command(gps_flight *f, int32_t row, const gp_command *cmd)
{
    gps_columns *c = &f->columns;
    c->state[row] = cmd->state;
    c->stack_depth[row] = (int8_t)cmd->stack_depth;
    c->profile[row] = (int8_t)cmd->profile;
    c->sensor_power[row] = (int32_t)cmd->sensor_power;
}

static void record_flight(gps_flight *f, int32_t row, int8_t phase, double out_cc,
                          double in_cc, uint8_t inflection)
{
    gps_columns *c = &f->columns;
    c->phase[row] = phase;
    c->pumped_out_cc[row] = out_cc;
    c->pumped_in_cc[row] = in_cc;
    c->inflection[row] = inflection;
    c->propulsion_w[row] = 0.0;
    f->block_j[row % GPS_GAUGE_TICKS] = bill(f, row);
}

/**
 * @brief Fly up to `ticks` ticks, each as sim/loop.py's simulate flies it with the
 *        runtime's step: the coulomb counter's reading, the science computer's SENSORS,
 *        the runtime's tick, the glider under its COMMAND, the tick's row and bill.
 * @return why it stopped: GPS_RAN, GPS_DONE (the run's last tick flown), GPS_ENDED (the
 *         mission exited, or its energy guard ended it), GPS_FAULT (a refused event:
 *         step.report), or what it needs to go on (GPS_NEED_NOISE, GPS_NEED_PITCH,
 *         GPS_TRACE_FULL): given that, call again and the tick goes on where it stopped.
 */
int gps_fly(gps_flight *f, int32_t ticks)
{
    const gps_physics *p = f->p;
    gps_columns *c = &f->columns;
    static const gp_command none = {0};
    for (int32_t n = 0; n < ticks; n++) {
        if (f->ended) {
            return f->ended;
        }
        int32_t tick = f->tick;
        if (tick > p->last_tick) {
            return GPS_DONE;
        }
        gp_command *cmd = &f->command;
        if (!f->pending) {
            if (f->stops_at_surfacings && f->surfacings != f->surfacings_seen) {
                f->surfacings_seen = f->surfacings;  /* as sim/loop.py's on_surfacing */
                return GPS_SURFACED;
            }
            if (f->normal_at >= GPS_NOISE_BLOCK || (p->spikes && f->spike_at >= GPS_NOISE_BLOCK)) {
                return GPS_NEED_NOISE;
            }
            if (f->n_trace + 3 > GPS_TRACE) {  /* a tick's transitions: 3 at most */
                return GPS_TRACE_FULL;
            }
            gauge(f, tick);
            double values[GP_N_SENSORS], water_c, reading_c;
            float sent[GP_N_SENSORS];
            uint32_t mask;
            c->depth_m[tick] = f->depth_m;
            c->pitch_rad[tick] = f->pitch_rad;
            c->lat_deg[tick] = f->lat_deg;
            c->lon_deg[tick] = f->lon_deg;
            sense(f, tick, values, &mask, &water_c, &reading_c);
            c->temperature_c[tick] = water_c;
            c->temp_reading_c[tick] = reading_c;
            for (int i = 0; i < GP_N_SENSORS; i++) {
                sent[i] = (float)values[i];
            }
            uint8_t last_state = f->step.runtime.machine.state;
            gp_tick_report *report = &f->report;
            gps_step_tick(&f->step, (uint32_t)tick, mask, sent, cmd, report);
            /* a refused event, or the envelope's fault action: the glider's own control
             * flies on, the run ends */
            if (report->fault || gps_step_releases(&f->step, report)) {
                gp_command refused = none;
                refused.state = last_state;
                record_command(f, tick, &refused);
                record_flight(f, tick, 0, 0.0, 0.0, 0);
                f->tick = tick + 1;
                f->ended = GPS_FAULT;
                return GPS_FAULT;
            }
            for (int i = 0; i < report->n_transitions; i++) {
                note(f, (uint32_t)tick, &report->transitions[i]);
            }
            record_command(f, tick, cmd);
            if (cmd->state == GPS_NO_STATE) {
                record_flight(f, tick, f->phase, 0.0, 0.0, 0);
                f->tick = tick + 1;
                f->ended = GPS_ENDED;
                return GPS_ENDED;
            }
            f->pending = 1;
            if (report->envelope.limit != GP_LIMIT_NONE) {  /* held at the limit */
                return GPS_ENVELOPE;
            }
        }
        int surface = (cmd->flags & GP_FLAG_SURFACE) != 0;
        if (speeds_missing(f, (double)cmd->pitch_rad, (double)cmd->ballast_cc, surface)) {
            return GPS_NEED_PITCH;
        }
        f->pending = 0;
        f->sensor_power = cmd->sensor_power;
        glider_step(f, (double)cmd->depth_target_m, (double)cmd->pitch_rad,
                    (double)cmd->ballast_cc, (double)cmd->heading_rad,
                    (cmd->flags & GP_FLAG_HEADING) != 0,
                    (cmd->flags & GP_FLAG_HEADING_HOLD) == 0, surface);
        if (f->grounded) {
            if (!f->grounded_ticks) {
                f->first_grounded_s = (double)tick * p->tick_s;
            }
            f->grounded_ticks++;
        }
        record_flight(f, tick, f->phase, f->pumped_out_cc, f->pumped_in_cc, f->inflection);
        f->tick = tick + 1;
    }
    return GPS_RAN;
}

/* ---- what the caller sets and reads ---------------------------------------------- */

/** @brief The glider and the science computer as the Python models start them:
 *         depth [m], pitch [rad], pumped volume [cc], heading [rad], true lat, lon,
 *         dead-reckoned lat, lon [deg], the CTD's flicker [degC] before the first tick,
 *         the current the glider measured, north and east [m/s]. */
void gps_flight_set(gps_flight *f, const double *v)
{
    f->depth_m = v[0];
    f->pitch_rad = v[1];
    f->ballast_cc = v[2];
    f->heading_rad = v[3];
    f->lat_deg = v[4];
    f->lon_deg = v[5];
    f->dr_lat_deg = v[6];
    f->dr_lon_deg = v[7];
    f->flicker_c = v[8];
    f->measured_north_mps = v[9];
    f->measured_east_mps = v[10];
    f->ticks_since_fix = 0;
    f->ctd_c = NAN;
    f->surface_time_s = -1.0;
    f->turning_to = f->turn_left_s = 0.0;
    f->phase = GPS_GLIDE;
    f->surfacings = f->grounded_ticks = f->surfacings_seen = 0;
    f->sensor_power = 0;
}

/** @brief From now on gps_fly returns GPS_SURFACED before the first tick after each
 *         surfacing, with that tick not begun. */
void gps_flight_stop_at_surfacings(gps_flight *f)
{
    f->stops_at_surfacings = 1;
}

/** @brief At a surfacing (GPS_SURFACED): the coulomb counter's reading before the next
 *         tick [J], the tick before which it was last brought up to date, the true lat,
 *         lon [deg]. */
void gps_flight_surfaced(gps_flight *f, double *out)
{
    out[0] = gauge(f, f->tick);
    out[1] = f->counted;
    out[2] = f->lat_deg;
    out[3] = f->lon_deg;
}

/** @brief Which blocks of random numbers are used up: out[0] the normals, out[1] the
 *         spikes (1: give the next one). */
void gps_flight_noise_at(const gps_flight *f, int32_t *out)
{
    out[0] = f->normal_at >= GPS_NOISE_BLOCK;
    out[1] = f->p->spikes && f->spike_at >= GPS_NOISE_BLOCK;
}

/** @brief The next tick, surfacings, ticks grounded, the time first grounded [s], the
 *         pitch whose glide speeds the loop wants [rad]. */
void gps_flight_status(const gps_flight *f, double *out)
{
    out[0] = f->tick;
    out[1] = f->surfacings;
    out[2] = f->grounded_ticks;
    out[3] = f->first_grounded_s;
    out[4] = f->need_pitch_rad;
}

/** @brief The transitions since the last call, into `out` (GPS_TRACE at most). */
int32_t gps_flight_take_trace(gps_flight *f, gps_transition *out)
{
    int32_t n = f->n_trace;
    memcpy(out, f->trace, (size_t)n * sizeof f->trace[0]);
    f->n_trace = 0;
    return n;
}

/** @brief The report of the last tick flown: its transitions, a refused event. */
void gps_flight_report(const gps_flight *f, gp_tick_report *out)
{
    *out = f->report;
}
