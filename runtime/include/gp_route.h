/**
 * @file gp_route.h
 * @brief Flight routes (docs/pilot.md): nav, noheading, a heading held or a steady
 *        turn (Slocum's set_heading), waypoints, Slocum's looping goto list, and the area sweep of a
 *        convex hull turned into lawn-mower waypoints.
 */
#ifndef GP_ROUTE_H
#define GP_ROUTE_H

#include <stdint.h>

#include "gp_mission.h"


/** Where the route is: the waypoint flown to, the waypoints reached, and the waypoints in
 *  decimal degrees. The waypoints come last: they follow from the route, so a checkpoint
 *  leaves them out. */
typedef struct {
    uint16_t next;                          /**< index of the waypoint flown to */
    uint16_t n_waypoints;
    uint32_t reached;                       /**< waypoints reached since entry (`wptreached`) */
    double turn_from_rad;                   /**< turn: the heading measured at entry */
    double waypoints[GP_MAX_SWEEP_WAYPOINTS][2];  /**< (lat, lon) [deg] */
} gp_route_state;

/** @brief Slocum DDMM.MMMM to decimal degrees. */
double gp_ddmm_to_deg(double ddmm);

/**
 * @brief Equirectangular offset of `to` from `from` about `from` [m north, m east].
 * @param from, to (lat, lon) [deg]
 */
void gp_offset_m(const double from[2], const double to[2], double *north_m, double *east_m);

/**
 * @brief Distance [m] from the current position (DDMM.MMMM readings) to the waypoint
 *        flown to; NaN without one (noheading) or without a position fix.
 */
double gp_route_distance_m(const gp_route_state *rs, const gp_route *route, double lat_ddmm,
                           double lon_ddmm);

/** @brief Enter a route: the first waypoint, waypoints from its points (sweep: the lawn-mower). */
void gp_route_enter(gp_route_state *rs, const gp_route *route);

/** @brief Fill the waypoints of a route, keeping `next` (for a resumed runtime). */
void gp_route_fill(gp_route_state *rs, const gp_route *route);

/**
 * @brief Heading to fly from the current position (DDMM.MMMM readings). A waypoint within
 *        the radius is reached: `reached` counts it, and the route flies on to the next
 *        (a list that does not loop counts its last once, then holds the heading to it).
 *        A heading route holds its heading, with or without a position fix.
 * @param heading_rad true heading, clockwise from north, [0, 2 pi)
 * @return 1 if the heading is valid, 0 (noheading, no position fix)
 */
int gp_route_step(gp_route_state *rs, const gp_route *route, double lat_ddmm, double lon_ddmm,
                  double *heading_rad);

/**
 * @brief Heading of a turn route `t_in_s` [s] after its entry: the heading measured at
 *        entry advanced at the route's rate, so a vehicle following it flies a spiral.
 * @param heading_rad true heading, clockwise from north, [0, 2 pi)
 * @return 1 if the heading is valid, 0 (no heading measured at entry)
 */
int gp_route_turn(const gp_route_state *rs, const gp_route *route, double t_in_s,
                  double *heading_rad);

/**
 * @brief Lawn-mower waypoints covering the convex hull of `corners` (DDMM.MMMM).
 * @param out (lat, lon) [deg], at most GP_MAX_SWEEP_WAYPOINTS
 * @return number of waypoints
 */
uint16_t gp_sweep_waypoints(const double (*corners)[2], uint8_t n_corners, double spacing_m,
                            double (*out)[2]);

#endif /* GP_ROUTE_H */
