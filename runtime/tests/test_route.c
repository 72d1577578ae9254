/* Routes of docs/pilot.md: positions, headings, waypoint advance, and the sweep.
 *
 *   sweep of a 1000 m square, spacing 200 m, north up: lines at 100, 300, ... 900 m,
 *   the first west to east, the next east to west (a lawn-mower).
 */
#include <math.h>

#include "gp_route.h"
#include "gp_test.h"

#define PI 3.14159265358979323846

static double deg_to_ddmm(double deg)
{
    double magnitude = fabs(deg);
    double whole = floor(magnitude);
    double ddmm = whole * 100 + (magnitude - whole) * 60;
    return deg < 0 ? -ddmm : ddmm;
}

/* A point `north_m`, `east_m` from (lat0, lon0) [deg], in DDMM.MMMM. */
static void local_point(double lat0, double lon0, double north_m, double east_m, double out[2])
{
    double scale = GP_EARTH_RADIUS_M * PI / 180.0;
    out[0] = deg_to_ddmm(lat0 + north_m / scale);
    out[1] = deg_to_ddmm(lon0 + east_m / (scale * cos(lat0 * PI / 180.0)));
}

/* The definition, with the C library's fmod: what the reference (sim/geo.py) computes. */
static double ddmm_by_fmod(double ddmm)
{
    double magnitude = fabs(ddmm);
    double deg = floor(magnitude / 100.0) + fmod(magnitude, 100.0) / 60.0;
    return ddmm < 0 ? -deg : deg;
}

/* Bit for bit, on random positions and on the values next to every hundred, where the
 * rounded quotient can land on the next whole number. */
void test_ddmm_should_equal_the_fmod_definition(void)
{
    unsigned seed = 7;
    for (int i = 0; i < 200000; i++) {
        double x = (gp_test_random(&seed) / 4294967296.0 - 0.5) * 36000.0;
        CHECK(gp_ddmm_to_deg(x) == ddmm_by_fmod(x));
    }
    for (int k = 0; k <= 180; k++) {
        double x = 100.0 * k;
        for (int step = 0; step < 8; step++) {
            CHECK(gp_ddmm_to_deg(x) == ddmm_by_fmod(x));
            CHECK(gp_ddmm_to_deg(-x) == ddmm_by_fmod(-x));
            x = nextafter(x, 0.0);
        }
    }
}

void test_ddmm_should_convert_to_degrees(void)
{
    CHECK_NEAR(gp_ddmm_to_deg(3910.5), 39.175, 1e-12);
    CHECK_NEAR(gp_ddmm_to_deg(-7349.8058), -(73 + 49.8058 / 60), 1e-12);
    CHECK_NEAR(gp_ddmm_to_deg(0.0), 0.0, 0);
}

void test_nav_should_head_to_its_point(void)
{
    static const struct { double north, east, heading; } rows[] = {
        {1000, 0, 0}, {0, 1000, PI / 2}, {-1000, 0, PI}, {0, -1000, 3 * PI / 2},
        {1000, 1000, PI / 4},
    };
    for (unsigned i = 0; i < sizeof rows / sizeof rows[0]; i++) {
        double target[1][2];
        local_point(44.0, -63.0, rows[i].north, rows[i].east, target[0]);
        gp_route route = {GP_ROUTE_NAV, 1, 0, (const double(*)[2])target};
        gp_route_state rs;
        double heading;
        gp_route_enter(&rs, &route);
        CHECK_INT(gp_route_step(&rs, &route, deg_to_ddmm(44.0), deg_to_ddmm(-63.0), &heading), 1);
        CHECK_NEAR(heading, rows[i].heading, 1e-3);
    }
}

void test_noheading_and_missing_fix_should_give_no_heading(void)
{
    double point[1][2] = {{4400, -6300}};
    gp_route nav = {GP_ROUTE_NAV, 1, 0, (const double(*)[2])point};
    gp_route none = {GP_ROUTE_NOHEADING, 0, 0, NULL};
    gp_route_state rs;
    double heading;
    gp_route_enter(&rs, &none);
    CHECK_INT(gp_route_step(&rs, &none, 4400, -6300, &heading), 0);
    gp_route_enter(&rs, &nav);
    CHECK_INT(gp_route_step(&rs, &nav, NAN, -6300, &heading), 0);
}

void test_heading_should_be_held_with_or_without_a_fix_and_reach_nothing(void)
{
    gp_route route = {GP_ROUTE_HEADING, 0, 4.0, NULL};  /* [rad] */
    gp_route_state rs;
    double heading;
    gp_route_enter(&rs, &route);
    CHECK_INT(gp_route_step(&rs, &route, 4400, -6300, &heading), 1);
    CHECK_NEAR(heading, 4.0, 0.0);
    CHECK_INT(gp_route_step(&rs, &route, NAN, NAN, &heading), 1);  /* a compass, no fix */
    CHECK_NEAR(heading, 4.0, 0.0);
    CHECK_INT(rs.reached, 0);
    CHECK_INT(isnan(gp_route_distance_m(&rs, &route, 4400, -6300)), 1);
}

void test_turn_should_advance_from_the_entry_heading_at_its_rate(void)
{
    gp_route route = {GP_ROUTE_TURN, 0, -0.02, NULL};  /* [rad/s], anticlockwise */
    gp_route_state rs;
    double heading;
    gp_route_enter(&rs, &route);
    rs.turn_from_rad = 0.5;
    CHECK_INT(gp_route_turn(&rs, &route, 0.0, &heading), 1);
    CHECK_NEAR(heading, 0.5, 1e-12);
    CHECK_INT(gp_route_turn(&rs, &route, 100.0, &heading), 1);  /* past north: wrapped */
    CHECK_NEAR(heading, 0.5 - 2.0 + 2.0 * 3.14159265358979323846, 1e-12);
    rs.turn_from_rad = NAN;  /* no heading measured at entry: none to turn from */
    CHECK_INT(gp_route_turn(&rs, &route, 10.0, &heading), 0);
}

void test_waypoints_should_advance_within_50_m_and_hold_the_last(void)
{
    double points[2][2];
    local_point(44.0, -63.0, 0, 1000, points[0]);     /* east */
    local_point(44.0, -63.0, 1000, 1000, points[1]);  /* then north-east */
    gp_route route = {GP_ROUTE_WAYPOINTS, 2, 0, (const double(*)[2])points};
    gp_route_state rs;
    double heading, here[2];
    gp_route_enter(&rs, &route);
    static const struct { double north, east, heading; int next, reached; } rows[] = {
        {0, 0, PI / 2, 0, 0},        /* toward p1 */
        {0, 960, 0, 1, 1},           /* within 50 m of p1: toward p2, due north */
        {0, 500, 0.463648, 1, 1},    /* never back to p1: atan2(500, 1000) */
        {1020, 1000, PI, 1, 2},      /* within 50 m of the last: reached, held toward */
        {1010, 1000, PI, 1, 2},      /* still within: the last counts once */
        {1200, 1000, PI, 1, 2},      /* past the last: hold toward it */
    };
    for (unsigned i = 0; i < sizeof rows / sizeof rows[0]; i++) {
        local_point(44.0, -63.0, rows[i].north, rows[i].east, here);
        CHECK_INT(gp_route_step(&rs, &route, here[0], here[1], &heading), 1);
        CHECK_NEAR(heading, rows[i].heading, 0.05);
        CHECK_INT(rs.next, rows[i].next);
        CHECK_INT(rs.reached, rows[i].reached);
    }
    gp_route nav = {GP_ROUTE_NAV, 1, 0, (const double(*)[2])points};
    gp_route_enter(&rs, &nav);
    local_point(44.0, -63.0, 0, 1000, here);  /* on its point: a heading, never reached */
    CHECK_INT(gp_route_step(&rs, &nav, here[0], here[1], &heading), 1);
    CHECK_INT(rs.reached, 0);
}

void test_goto_list_should_loop_with_its_radius_and_report_the_distance(void)
{
    double points[2][2];
    local_point(44.0, -63.0, 0, 1000, points[0]);
    local_point(44.0, -63.0, 1000, 1000, points[1]);
    gp_route route = {GP_ROUTE_GOTO_LIST, 2, 200, (const double(*)[2])points};
    gp_route_state rs;
    double heading, here[2];
    gp_route_enter(&rs, &route);
    static const struct { double north, east, distance; int next, reached; } rows[] = {
        {0, 0, 1000, 0, 0},          /* toward p1, 1 km away */
        {0, 790, 210, 0, 0},         /* outside the 200 m radius */
        {0, 810, 190, 1, 1},         /* inside: toward p2 */
        {850, 1000, 150, 0, 2},      /* p2 reached: the list starts again at p1 */
        {500, 1000, 500, 0, 2},
        {0, 900, 100, 1, 3},         /* p1 again: the count goes on, lap after lap */
    };
    for (unsigned i = 0; i < sizeof rows / sizeof rows[0]; i++) {
        local_point(44.0, -63.0, rows[i].north, rows[i].east, here);
        CHECK_NEAR(gp_route_distance_m(&rs, &route, here[0], here[1]), rows[i].distance, 0.5);
        CHECK_INT(gp_route_step(&rs, &route, here[0], here[1], &heading), 1);
        CHECK_INT(rs.next, rows[i].next);
        CHECK_INT(rs.reached, rows[i].reached);
    }
    CHECK(isnan(gp_route_distance_m(&rs, &route, NAN, here[1])));
    gp_route none = {GP_ROUTE_NOHEADING, 0, 0, NULL};
    gp_route_enter(&rs, &none);
    CHECK(isnan(gp_route_distance_m(&rs, &none, here[0], here[1])));
}

static void to_local(const double origin[2], const double wp[2], double *north, double *east)
{
    gp_offset_m(origin, wp, north, east);
}

void test_sweep_should_mow_a_square_in_alternating_lines(void)
{
    double corners[5][2];
    local_point(44.0, -63.0, 0, 0, corners[0]);
    local_point(44.0, -63.0, 1000, 1000, corners[1]);  /* out of order on purpose */
    local_point(44.0, -63.0, 0, 1000, corners[2]);
    local_point(44.0, -63.0, 500, 500, corners[3]);    /* inside: not a hull vertex */
    local_point(44.0, -63.0, 1000, 0, corners[4]);
    static double out[GP_MAX_SWEEP_WAYPOINTS][2];
    uint16_t n = gp_sweep_waypoints((const double(*)[2])corners, 5, 200, out);
    CHECK_INT(n, 10);
    double origin[2] = {gp_ddmm_to_deg(corners[0][0]), gp_ddmm_to_deg(corners[0][1])};
    for (int line = 0; line < 5 && 2 * line + 1 < n; line++) {
        double n0, e0, n1, e1;
        to_local(origin, out[2 * line], &n0, &e0);
        to_local(origin, out[2 * line + 1], &n1, &e1);
        CHECK_NEAR(n0, 100 + 200 * line, 0.01);
        CHECK_NEAR(n1, 100 + 200 * line, 0.01);
        CHECK_NEAR(e0, line % 2 ? 1000 : 0, 0.01);
        CHECK_NEAR(e1, line % 2 ? 0 : 1000, 0.01);
    }
}

void test_sweep_should_clip_lines_to_a_triangle(void)
{
    double corners[3][2];
    local_point(44.0, -63.0, 0, 0, corners[0]);
    local_point(44.0, -63.0, 0, 1000, corners[1]);
    local_point(44.0, -63.0, 1000, 0, corners[2]);
    static double out[GP_MAX_SWEEP_WAYPOINTS][2];
    uint16_t n = gp_sweep_waypoints((const double(*)[2])corners, 3, 500, out);
    CHECK_INT(n, 4);  /* lines at 250 m and 750 m */
    double origin[2] = {gp_ddmm_to_deg(corners[0][0]), gp_ddmm_to_deg(corners[0][1])};
    double north, east;
    to_local(origin, out[1], &north, &east);
    CHECK_NEAR(east, 750, 0.05);   /* the hypotenuse x + y = 1000 at y = 250 */
    to_local(origin, out[2], &north, &east);
    CHECK_NEAR(east, 250, 0.05);   /* second line starts in the east */
}

void test_sweep_should_stop_at_256_waypoints(void)
{
    double corners[3][2];
    local_point(44.0, -63.0, 0, 0, corners[0]);
    local_point(44.0, -63.0, 0, 5000, corners[1]);
    local_point(44.0, -63.0, 5000, 0, corners[2]);
    static double out[GP_MAX_SWEEP_WAYPOINTS][2];
    CHECK_INT(gp_sweep_waypoints((const double(*)[2])corners, 3, 1.0, out), GP_MAX_SWEEP_WAYPOINTS);
    CHECK_INT(gp_sweep_waypoints((const double(*)[2])corners, 3, 0.0, out), 0);
}

/* As many corners as a route holds (the checker's limit for a sweep): every one is read.
 * A regular polygon of radius 1000 m: each line's ends lie on its edges, between the
 * inscribed circle (radius 1000 cos(pi/n)) and the circle through the corners. */
void test_sweep_should_read_every_corner_a_route_holds(void)
{
    double corners[GP_MAX_ROUTE_POINTS][2];
    for (int k = 0; k < GP_MAX_ROUTE_POINTS; k++) {
        double angle = 2 * PI * k / GP_MAX_ROUTE_POINTS;
        local_point(44.0, -63.0, 1000 * sin(angle), 1000 * cos(angle), corners[k]);
    }
    static double out[GP_MAX_SWEEP_WAYPOINTS][2];
    uint16_t n = gp_sweep_waypoints((const double(*)[2])corners, GP_MAX_ROUTE_POINTS, 200, out);
    CHECK_INT(n, 20);  /* 10 lines across 2000 m */
    double origin[2] = {gp_ddmm_to_deg(corners[0][0]), gp_ddmm_to_deg(corners[0][1])};
    double inscribed = 1000 * cos(PI / GP_MAX_ROUTE_POINTS);
    for (int i = 0; i < n; i++) {
        double north, east;
        to_local(origin, out[i], &north, &east);
        double radius = hypot(east + 1000, north);  /* the centre is 1000 m west of corner 0 */
        CHECK(radius >= inscribed - 0.05 && radius <= 1000.05);
    }
}
