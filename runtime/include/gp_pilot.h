/**
 * @file gp_pilot.h
 * @brief Flight profiles as docs/pilot.md specifies them: yo, thermotrackyo (robust
 *        and naive thermocline trackers), surface, hover, and on a propeller cruise and
 *        altitude. Pure state machines over
 *        depth and temperature readings; no I/O.
 */
#ifndef GP_PILOT_H
#define GP_PILOT_H

#include <stdint.h>

#include "gp_mission.h"


typedef enum { GP_LEG_DIVE = 0, GP_LEG_CLIMB = 1 } gp_leg;

typedef struct {
    double depth_m, temp_c;
} gp_reading;

/** What the pilot remembers while flying one profile (reset on entry). */
typedef struct {
    uint8_t leg;                 /**< gp_leg */
    uint8_t detected;            /**< thermocline detected on this leg */
    uint8_t n_window;
    uint8_t n_recent;            /**< raw temperatures of the leg for the median (<= 3) */
    uint32_t halfcycle;          /**< yo: the leg flown, 1 the first; 0 for other profiles */
    double lo_m, hi_m;           /**< tracked band (thermotrackyo), else min/max */
    double recent_c[3];          /**< last raw temperatures of the leg, oldest first */
    double previous_c;           /**< naive: previous raw temperature of the leg */
    gp_reading window[GP_TRACK_WINDOW];  /**< oldest first */
    /* What the robust tracker knows of the window without walking it: its shallowest
     * and deepest reading, its warmest and coldest (the first of equals). Derived, never
     * checkpointed: 0 in `summarized` (a resumed runtime) walks the window again. */
    uint8_t summarized;
    uint8_t warmest, coldest;
    double shallowest_m, deepest_m;
} gp_pilot;

/** The vertical part of a COMMAND, and the propulsion's. */
typedef struct {
    double depth_target_m, pitch_rad, ballast_cc;
    uint8_t flags;               /**< GP_FLAG_SURFACE, GP_FLAG_CLIMBING */
    double speed_mps;            /**< cruise, altitude: through the water [m/s]; else 0 */
    double thrust_w;             /**< yo, thermotrackyo: the thruster's power [W]; else 0 */
} gp_pilot_command;

/** Profile inputs for one tick. */
typedef struct {
    uint8_t kind;                /**< gp_profile_kind */
    double args[GP_MAX_PROFILE_ARGS];
    double plan_pitch_rad;       /**< NaN: the profile's own pitch arguments */
    double ballast_cc;           /**< B: the plan's, or the mission's default */
    uint8_t naive;               /**< thermotrackyo: the paper's first, naive tracker */
    double plan_speed_mps;       /**< NaN: no plan; cruise and altitude fly their speed
                                      argument, or `unplanned_speed_mps` for `auto` */
    double unplanned_speed_mps;  /**< the mission's (gp_mission) */
    double thrust_w;             /**< a yo's thruster [W]: the plan's, else the one written */
} gp_profile_input;

/** What the pilot did this tick: turned the yo, detected the thermocline. */
enum { GP_PILOT_TURNED = 1, GP_PILOT_DETECTED = 2 };

/**
 * @brief Enter a profile: band = [min, max], window empty, leg from the depth and the
 *        altimeter (a yo enters climbing at or below its altimeter stop).
 * @param altitude_m the altitude reading, height above the sea floor [m] (NaN: none)
 */
void gp_pilot_enter(gp_pilot *pilot, const gp_profile_input *in, double depth_m,
                    double altitude_m);

/**
 * @brief One tick of the profile: turn the leg if due (a dive at the band's bottom, or
 *        at the yo's altimeter stop), track the thermocline, command depth target, pitch
 *        and ballast.
 * @param altitude_m the altitude reading [m]; NaN (out of range) never turns a dive
 * @return GP_PILOT_TURNED | GP_PILOT_DETECTED bits
 */
int gp_pilot_step(gp_pilot *pilot, const gp_profile_input *in, double depth_m, double temp_c,
                  double altitude_m, gp_pilot_command *out);

#endif /* GP_PILOT_H */
