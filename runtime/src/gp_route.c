/* Routes and the sweep planner. Local geometry is equirectangular about one point:
 * gliders sweep areas of a few kilometres, where the error is far below GPS noise. */
#include "gp_route.h"

#include <math.h>
#include <stddef.h>

#define GP_PI 3.14159265358979323846

/* floor(|x| / 100) + fmod(|x|, 100) / 60 with its sign, as the reference computes it.
 * The minutes are fmod's, exactly, without fmod (a hundred instructions twice a tick):
 * with q = floor(|x| / 100), |x| - 100 q is exact (Sterbenz: 100 q and |x| lie within
 * a factor of two, or q = 0), and the rounded quotient is never below the true one, so
 * at most once too high, when the difference is negative and 100 more is the remainder. */
double gp_ddmm_to_deg(double ddmm)
{
    double magnitude = fabs(ddmm);
    double hundreds = floor(magnitude / 100.0);
    double minutes = magnitude - 100.0 * hundreds;
    if (minutes < 0) {
        minutes += 100.0;
    }
    double deg = hundreds + minutes / 60.0;
    return ddmm < 0 ? -deg : deg;
}

void gp_offset_m(const double from[2], const double to[2], double *north_m, double *east_m)
{
    double scale = GP_EARTH_RADIUS_M * GP_PI / 180.0;
    *north_m = (to[0] - from[0]) * scale;
    *east_m = (to[1] - from[1]) * scale * cos(from[0] * GP_PI / 180.0);
}

/* The length of an offset [m]: the square root of the sum of squares, each operation
 * rounded once, as the reference computes it (docs/pilot.md); not the C library's hypot,
 * whose last bit differs between libraries, and between them and Python's. */
static double length_m(double north_m, double east_m)
{
    return sqrt(north_m * north_m + east_m * east_m);
}

/* @param distance_m NULL when the distance is not wanted (a nav route never arrives) */
static double heading_to(const double from[2], const double to[2], double *distance_m)
{
    double north, east;
    gp_offset_m(from, to, &north, &east);
    if (distance_m) {
        *distance_m = length_m(north, east);
    }
    double heading = atan2(east, north);
    return heading < 0 ? heading + 2.0 * GP_PI : heading;
}

/* ---- sweep ------------------------------------------------------------------- */

typedef struct {
    double x, y;  /* east, north [m] */
} point;

static double cross(point o, point a, point b)
{
    return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x);
}

/* Andrew's monotone chain; `p` sorted in place; hull counter-clockwise in `hull`. */
static int convex_hull(point *p, int n, point *hull)
{
    for (int i = 1; i < n; i++) {  /* insertion sort by (x, y): n <= GP_MAX_ROUTE_POINTS */
        point key = p[i];
        int j = i - 1;
        while (j >= 0 && (p[j].x > key.x || (p[j].x == key.x && p[j].y > key.y))) {
            p[j + 1] = p[j];
            j--;
        }
        p[j + 1] = key;
    }
    if (n < 3) {
        for (int i = 0; i < n; i++) {
            hull[i] = p[i];
        }
        return n;
    }
    int k = 0;
    for (int i = 0; i < n; i++) {
        while (k >= 2 && cross(hull[k - 2], hull[k - 1], p[i]) <= 0) {
            k--;
        }
        hull[k++] = p[i];
    }
    for (int i = n - 2, lower = k + 1; i >= 0; i--) {
        while (k >= lower && cross(hull[k - 2], hull[k - 1], p[i]) <= 0) {
            k--;
        }
        hull[k++] = p[i];
    }
    return k - 1;
}

/* West and east ends of the hull's cut at northing y. @return 0 if it misses. */
static int clip_line(const point *hull, int n, double y, double *west, double *east)
{
    int hit = 0;
    for (int i = 0; i < n; i++) {
        point a = hull[i], b = hull[(i + 1) % n];
        double x;
        if (a.y == b.y) {
            if (a.y != y) {
                continue;
            }
            x = fmin(a.x, b.x);
            *west = hit ? fmin(*west, x) : x;
            *east = hit ? fmax(*east, fmax(a.x, b.x)) : fmax(a.x, b.x);
            hit = 1;
            continue;
        }
        if (y < fmin(a.y, b.y) || y > fmax(a.y, b.y)) {
            continue;
        }
        x = a.x + (y - a.y) * (b.x - a.x) / (b.y - a.y);
        *west = hit ? fmin(*west, x) : x;
        *east = hit ? fmax(*east, x) : x;
        hit = 1;
    }
    return hit;
}

uint16_t gp_sweep_waypoints(const double (*corners)[2], uint8_t n_corners, double spacing_m,
                            double (*out)[2])
{
    point p[GP_MAX_ROUTE_POINTS], hull[2 * GP_MAX_ROUTE_POINTS];
    int n = n_corners > GP_MAX_ROUTE_POINTS ? GP_MAX_ROUTE_POINTS : n_corners;
    if (n == 0 || !(spacing_m > 0)) {
        return 0;
    }
    double origin[2] = {gp_ddmm_to_deg(corners[0][0]), gp_ddmm_to_deg(corners[0][1])};
    for (int i = 0; i < n; i++) {
        double corner[2] = {gp_ddmm_to_deg(corners[i][0]), gp_ddmm_to_deg(corners[i][1])};
        gp_offset_m(origin, corner, &p[i].y, &p[i].x);
    }
    int h = convex_hull(p, n, hull);
    double south = hull[0].y, north = hull[0].y;
    for (int i = 1; i < h; i++) {
        south = fmin(south, hull[i].y);
        north = fmax(north, hull[i].y);
    }
    double scale = GP_EARTH_RADIUS_M * GP_PI / 180.0;
    double east_scale = scale * cos(origin[0] * GP_PI / 180.0);
    uint16_t count = 0;
    for (int line = 0; count + 2 <= GP_MAX_SWEEP_WAYPOINTS; line++) {
        double y = south + spacing_m / 2.0 + line * spacing_m;
        double west, east;
        if (y > north || !clip_line(hull, h, y, &west, &east)) {
            break;
        }
        double first = (line % 2 == 0) ? west : east, second = (line % 2 == 0) ? east : west;
        double lat = origin[0] + y / scale;
        out[count][0] = lat;
        out[count++][1] = origin[1] + first / east_scale;
        out[count][0] = lat;
        out[count++][1] = origin[1] + second / east_scale;
    }
    return count;
}

/* ---- routes ------------------------------------------------------------------ */

void gp_route_enter(gp_route_state *rs, const gp_route *route)
{
    rs->next = 0;
    rs->reached = 0;
    gp_route_fill(rs, route);
}

void gp_route_fill(gp_route_state *rs, const gp_route *route)
{
    rs->n_waypoints = 0;
    if (route->kind == GP_ROUTE_SWEEP) {
        rs->n_waypoints = gp_sweep_waypoints(route->points, route->n_points, route->param,
                                             rs->waypoints);
        return;
    }
    if (route->kind == GP_ROUTE_NOHEADING || route->kind == GP_ROUTE_HEADING) {
        return;
    }
    for (int i = 0; i < route->n_points && i < GP_MAX_ROUTE_POINTS; i++) {
        rs->waypoints[i][0] = gp_ddmm_to_deg(route->points[i][0]);
        rs->waypoints[i][1] = gp_ddmm_to_deg(route->points[i][1]);
        rs->n_waypoints++;
    }
}

double gp_route_distance_m(const gp_route_state *rs, const gp_route *route, double lat_ddmm,
                           double lon_ddmm)
{
    if (route->kind == GP_ROUTE_NOHEADING || rs->n_waypoints == 0
        || !isfinite(lat_ddmm) || !isfinite(lon_ddmm)) {
        return NAN;
    }
    double here[2] = {gp_ddmm_to_deg(lat_ddmm), gp_ddmm_to_deg(lon_ddmm)};
    double north, east;
    gp_offset_m(here, rs->waypoints[rs->next], &north, &east);
    return length_m(north, east);
}

int gp_route_turn(const gp_route_state *rs, const gp_route *route, double t_in_s,
                  double *heading_rad)
{
    *heading_rad = 0.0;
    if (!isfinite(rs->turn_from_rad) || !isfinite(t_in_s)) {
        return 0;
    }
    double heading = fmod(rs->turn_from_rad + route->param * t_in_s, 2.0 * GP_PI);
    *heading_rad = heading < 0.0 ? heading + 2.0 * GP_PI : heading;
    return 1;
}

int gp_route_step(gp_route_state *rs, const gp_route *route, double lat_ddmm, double lon_ddmm,
                  double *heading_rad)
{
    *heading_rad = 0.0;
    if (route->kind == GP_ROUTE_HEADING) {  /* a compass needs no position fix */
        *heading_rad = route->param;
        return 1;
    }
    if (route->kind == GP_ROUTE_NOHEADING || rs->n_waypoints == 0
        || !isfinite(lat_ddmm) || !isfinite(lon_ddmm)) {
        return 0;
    }
    double here[2] = {gp_ddmm_to_deg(lat_ddmm), gp_ddmm_to_deg(lon_ddmm)};
    int arrives = route->kind != GP_ROUTE_NAV;
    double distance_m = 0;
    double heading = heading_to(here, rs->waypoints[rs->next], arrives ? &distance_m : NULL);
    /* One waypoint per tick at most; after the last, hold the heading to it (a goto
     * list starts again from the first). A list that does not loop reaches one waypoint
     * per advance, so it has reached its last once it has reached more than its index. */
    int loops = route->kind == GP_ROUTE_GOTO_LIST;
    int advances = loops || rs->next + 1 < rs->n_waypoints;
    double radius_m = loops ? route->param : GP_WAYPOINT_RADIUS_M;
    if (arrives && distance_m <= radius_m && (advances || rs->reached <= rs->next)) {
        if (rs->reached < UINT32_MAX) {
            rs->reached++;
        }
        if (advances) {
            rs->next = (uint16_t)((rs->next + 1) % rs->n_waypoints);
            heading = heading_to(here, rs->waypoints[rs->next], &distance_m);
        }
    }
    *heading_rad = heading;
    return 1;
}
