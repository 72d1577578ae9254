/* The fast executor's inner loops (sim/fast.py), in C for speed, and the C library's
 * mathematical functions over arrays (sim/libm.py).
 *
 * Each function gives the very numbers the simulator's Python reference computes one
 * tick at a time: the same operations on doubles in the same order, the same C library
 * functions (Python's math module calls them too, in the same process), binary32 through
 * a cast (as struct's 'f'), and no a*b+c contracted into one rounding (built with
 * -ffp-contract=off). A loop stops where it cannot decide a tick as the reference would
 * and says so; the caller's tick-by-tick loop flies that tick. No allocation: the caller
 * passes every array, sized as each function says. */
#include <math.h>

#define GPN_PI 3.14159265358979323846

/* ---- the C library over arrays ------------------------------------------------- */

void gpn_sin(const double *x, double *out, long n)
{
    for (long i = 0; i < n; i++) {
        out[i] = sin(x[i]);
    }
}

void gpn_cos(const double *x, double *out, long n)
{
    for (long i = 0; i < n; i++) {
        out[i] = cos(x[i]);
    }
}

void gpn_tanh(const double *x, double *out, long n)
{
    for (long i = 0; i < n; i++) {
        out[i] = tanh(x[i]);
    }
}

void gpn_atan2(const double *y, const double *x, double *out, long n)
{
    for (long i = 0; i < n; i++) {
        out[i] = atan2(y[i], x[i]);
    }
}

/* ---- the CTD's lag (science.first_order_lag) ------------------------------------ */

/* c[i] = w[i] + (c[i-1] - w[i]) keep, c = w where the one before is NaN; `before`:
 * the lagged temperature before the first. */
void gpn_lag(const double *water_c, long n, double before, double keep, double *lagged_c)
{
    double c = before;
    for (long i = 0; i < n; i++) {
        double w = water_c[i];
        c = c != c ? w : w + (c - w) * keep;
        lagged_c[i] = c;
    }
}

/* ---- a yo leg of a compressible hull (fast._SqueezedLeg) ------------------------ */

static double binary32(double x)
{
    return (double)(float)x;
}

/* Whether the depth reading (depth + noise, clamped at 0, binary32) reaches the band's
 * edge; decided in double precision where binary32's rounding cannot change it. */
static int reaches(double depth_m, double edge, int diving)
{
    double reading = depth_m > 0.0 ? depth_m : 0.0;
    double scale = fabs(edge) > 1.0 ? fabs(edge) : 1.0;
    if (fabs(reading - edge) <= 1e-6 * scale) {
        reading = binary32(reading);
    }
    return diving ? reading >= edge : reading <= edge;
}

/* The water's buoyancy [cc] at depth `d` [m] from its table (`n` values every `step` m
 * from the surface, linear between, held beyond the last): vehicle.Stratification.at,
 * the same operations in the same order. */
static double lift_at(const double *lift, long n, double step, double d)
{
    double x = d / step;
    if (!(x < (double)(n - 1))) {
        return lift[n - 1];
    }
    if (x <= 0.0) {
        return lift[0];
    }
    long i = (long)x;
    return lift[i] + (lift[i + 1] - lift[i]) * (x - (double)i);
}

/* The water a leg flies through: no table (n 0, uniform water of the reference density)
 * or vehicle.Stratification's. */
typedef struct {
    const double *lift;
    long n;
    double step;
} water;

/* The ticks of one yo leg from depth `depths_m[0]`, at most `limit`: tick t (from 1)
 * flies row min(t - 1, settled) of `rows` (4 numbers a row: sign of the buoyancy,
 * volume plus trim [cc], signed vertical speed per square root of a cc [m s-1], time
 * gliding [s]); its depth is the last plus speed sqrt(max(0, sign (base - squeeze
 * (weight d) [+ lift(d)]))) glide_s, the water's lift where it has a table. The leg ends on the first tick t < limit whose reading, its
 * depth plus noise[t], reaches `edge` (only a depth beyond `near` is tried), or before
 * a depth the glider would clamp at the surface (*stop = 1). Writes depths_m[1..] and
 * returns the leg's ticks. */
static long leg(const double *rows, long settled, double weight, double squeeze,
                const water *w, const double *noise, double near, double edge, int diving,
                long limit, double *depths_m, int *stop)
{
    double d = depths_m[0];
    for (long t = 1; t <= limit; t++) {
        const double *row = rows + 4 * (t - 1 < settled ? t - 1 : settled);
        double glide_s = row[3];
        if (t > settled || glide_s != 0.0) {  /* settling: pumping or turning all tick */
            double net = row[1] - squeeze * (weight * d);
            if (w->n > 0) {
                net = net + lift_at(w->lift, w->n, w->step, d);
            }
            double x = row[0] * net;
            d = d + row[2] * sqrt(x < 0.0 ? 0.0 : x) * glide_s;
            if (d < 0.0) {  /* the glider would clamp it at the surface */
                *stop = 1;
                return t - 1;
            }
        }
        depths_m[t] = d;
        if ((diving ? d >= near : d <= near) && t < limit && reaches(d + noise[t], edge, diving)) {
            return t;
        }
    }
    return limit;
}

/* A yo of a compressible hull (or through stratified water: `lift`, `n_lift` values every
 * `lift_step` m, n_lift 0 for none) over `count` ticks, leg after leg from `depths_m[0]`:
 * the first leg (direction `dive`: 1 diving, 0 climbing) flies glide 0, then the legs
 * alternate between glides 1 and 2 (those from the actuators settled by the leg before)
 * as long as each leg lasts until its glide settles. `rows[g]`, `settled[g]`: glide g's
 * rows (`leg`), `glides` of them given (1: the first leg alone). `near`, `edge`: per
 * direction, climbing first. Writes depths_m[1..] and `legs` (first tick and ticks of each
 * leg, 2 numbers a leg, count + 1 legs at most); *stop = 1 when the run must stop before
 * a tick that would clamp at the surface. Returns the number of legs. */
long gpn_squeezed_yo(const double *const *rows, const long *settled, long glides,
                     double weight, double squeeze, const double *lift, long n_lift,
                     double lift_step, const double *noise, const double *near,
                     const double *edge, int dive, long count, double *depths_m, long *legs,
                     int *stop)
{
    long j = 0, n = 0;
    water w = {lift, n_lift, lift_step};
    *stop = 0;
    while (j < count) {
        long g = n == 0 ? 0 : 2 - n % 2;
        long ticks = leg(rows[g], settled[g], weight, squeeze, &w, noise + j, near[dive],
                         edge[dive], dive, count - j, depths_m + j, stop);
        if (ticks == 0 && *stop) {
            break;
        }
        legs[2 * n] = j;
        legs[2 * n + 1] = ticks;
        n++;
        j += ticks;
        dive = !dive;
        if (*stop || glides == 1 || ticks < settled[g]) {
            break;  /* clamped, or the next leg starts from unsettled actuators */
        }
    }
    return n;
}

/* ---- the route to a waypoint (fast.FastForward._route) --------------------------- */

/* floor(|x| / 100) + fmod(|x|, 100) / 60 with the sign of x (geo.ddmm_to_degrees), the
 * minutes fmod's exactly without fmod (as the runtime's gp_ddmm_to_deg): with
 * q = floor(|x| / 100), |x| - 100 q is exact (Sterbenz), and q is at most once too high,
 * when the difference is negative and 100 more is the remainder. */
static double ddmm_to_degrees(double x)
{
    double a = fabs(x);
    double hundreds = floor(a / 100.0);
    double minutes = a - 100.0 * hundreds;
    if (minutes < 0.0) {
        minutes += 100.0;
    }
    return copysign(hundreds + minutes / 60.0, x);
}

static double degrees_to_ddmm(double x)
{
    double a = fabs(x);
    double whole = floor(a);
    return copysign(whole * 100.0 + (a - whole) * 60.0, x);
}

/* geo.move_degrees */
static void move(double *lat, double *lon, double north_m, double east_m, double radius_m)
{
    double rad = GPN_PI / 180.0;
    double lat0 = *lat;
    *lat = lat0 + north_m / (radius_m * rad);
    *lon = *lon + east_m / (radius_m * cos(lat0 * rad) * rad);
}

/* Ticks of a route toward one waypoint (`target`: lat, lon [deg]), one at a time as the
 * runtime steers: the heading from this tick's position readings (dead reckoned,
 * DDMM.MMMM through binary32), to binary32 as the COMMAND carries it; then the glider
 * moves `distance_m[j]` along it, and with the current (`current`: north, east [m s-1]
 * over `tick_s`); on tick `fix_at` the dead reckoning is first set to the true position.
 * `positions`: 4 (count + 1) numbers, dead-reckoned lat, lon, true lat, lon [deg], each
 * before every tick and after the last (the first of each given); `heading_rad`: count.
 * Returns the first tick on which the waypoint may be reached (when `advance`: within
 * `reach_m`, or so near it that only the route's own hypot can tell), else count. */
long gpn_route(const double *target, double reach_m, int advance, const double *distance_m,
               long count, long fix_at, double tick_s, const double *current,
               double radius_m, double *positions, double *heading_rad)
{
    double *dr_lat = positions, *dr_lon = positions + count + 1;
    double *lat = positions + 2 * (count + 1), *lon = positions + 3 * (count + 1);
    double scale = radius_m * GPN_PI / 180.0;
    int drifts = current[0] != 0.0 || current[1] != 0.0;
    for (long j = 0; j < count; j++) {
        double lat_deg = ddmm_to_degrees(binary32(degrees_to_ddmm(dr_lat[j])));
        double lon_deg = ddmm_to_degrees(binary32(degrees_to_ddmm(dr_lon[j])));
        double north = (target[0] - lat_deg) * scale;
        double east = (target[1] - lon_deg) * scale * cos(lat_deg * GPN_PI / 180.0);
        if (advance && hypot(north, east) <= reach_m * (1.0 + 1e-9)) {
            return j;
        }
        double heading = atan2(east, north);
        heading = binary32(heading < 0.0 ? heading + 2.0 * GPN_PI : heading);
        heading_rad[j] = heading;
        double drl = dr_lat[j], drn = dr_lon[j], tl = lat[j], tn = lon[j];
        if (j == fix_at) {
            drl = tl;
            drn = tn;
        }
        double n = distance_m[j] * cos(heading), e = distance_m[j] * sin(heading);
        if (n != 0.0 || e != 0.0) {
            move(&drl, &drn, n, e, radius_m);
        }
        if (drifts) {
            move(&tl, &tn, n + current[0] * tick_s, e + current[1] * tick_s, radius_m);
        } else {
            tl = drl;
            tn = drn;
        }
        dr_lat[j + 1] = drl;
        dr_lon[j + 1] = drn;
        lat[j + 1] = tl;
        lon[j + 1] = tn;
    }
    return count;
}
