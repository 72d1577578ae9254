/**
 * @file gp_mission.h
 * @brief The compiled mission: constant tables the code generator emits
 *        (language/codegen_c.py) and the runtime executes.
 *
 * One generated C file defines `gp_mission_table` and the functions it points to.
 * Everything is `const` and static: the runtime allocates nothing.
 * Indices of sensors are those of gliderplan.language.registry.SENSORS.
 */
#ifndef GP_MISSION_H
#define GP_MISSION_H

#include <stdint.h>

#define GP_N_SENSORS 17      /**< length of the sensor array (registry) */
#define GP_MAX_STATES 64     /**< plan-format limit */
#define GP_MAX_VARIABLES 64
#define GP_MAX_PROFILES 8    /**< alternatives per state */
#define GP_MAX_PROFILE_ARGS 6
#define GP_MAX_POINTS 64     /**< route points per state */
#define GP_MAX_STACK 32      /**< upper bound of a mission's stack_depth */

/** Action of an event. */
typedef enum {
    GP_ACT_NONE = 0,   /**< assignments only, no transition */
    GP_ACT_GOTO = 2,
    GP_ACT_CALL = 3,
    GP_ACT_RETURN = 4,
    GP_ACT_EXIT = 5,
} gp_action;

typedef enum {
    GP_PROFILE_YO = 0,
    GP_PROFILE_THERMOTRACKYO = 1,
    GP_PROFILE_SURFACE = 2,
    GP_PROFILE_HOVER = 3,
} gp_profile_kind;

typedef enum {
    GP_ROUTE_NAV = 0,
    GP_ROUTE_NOHEADING = 1,
    GP_ROUTE_WAYPOINTS = 2,
    GP_ROUTE_SWEEP = 3,
} gp_route_kind;

/**
 * @brief Condition of an event, with C semantics for the language's expressions.
 * @param sensors GP_N_SENSORS values [registry units]
 * @param vars    the mission's variables
 * @return non-zero if the condition holds
 */
typedef int (*gp_condition_fn)(const double *sensors, const double *vars);

/** @brief Run an event's assignments in order (each sees the ones before). */
typedef void (*gp_assign_fn)(const double *sensors, double *vars);

/** @brief Evaluate a profile's arguments (they may read variables) into `args`. */
typedef void (*gp_args_fn)(const double *sensors, const double *vars, double *args);

typedef struct {
    gp_condition_fn condition;
    gp_assign_fn assign;   /**< NULL when the event has no assignments */
    uint8_t action;        /**< gp_action */
    uint8_t target;        /**< state index for GOTO and CALL, else 0 */
} gp_event;

typedef struct {
    uint8_t kind;          /**< gp_profile_kind */
    uint8_t n_args;
    gp_args_fn args;       /**< fills n_args values [m, rad, degC as the registry says] */
} gp_profile;

typedef struct {
    uint8_t kind;          /**< gp_route_kind */
    uint8_t n_points;
    double param;          /**< nav: unused; sweep: line spacing [m] */
    const double (*points)[2];  /**< (lat, lon) DDMM.MMMM; nav has one point */
} gp_route;

typedef struct {
    const char *name;
    gp_route route;
    const gp_profile *profiles;  /**< alternatives, in source order */
    uint8_t n_profiles;          /**< 1..GP_MAX_PROFILES */
    const uint8_t *sensors;      /**< sensor indices the state logs, in source order */
    uint8_t n_sensors;
    const gp_event *events;      /**< checked in order each tick; the first true fires */
    uint8_t n_events;
} gp_state;

typedef struct {
    const char *name;
    const char *hash;             /**< CheckedMission.hash, 64 lowercase hex digits */
    const gp_state *states;       /**< states[0] is the start state */
    uint8_t n_states;
    const double *var_initial;    /**< initial values of the variables */
    uint8_t n_vars;
    uint8_t stack_depth;          /**< 1..GP_MAX_STACK */
    uint32_t read_mask;           /**< sensors the mission reads (bit i: sensor i) */
    double default_ballast_cc;    /**< pumped volume when no plan sets one [cc] */
    const char *const *sensor_names;  /**< GP_N_SENSORS names, registry order */
} gp_mission;

/** The mission this binary was compiled for (defined by the generated file). */
extern const gp_mission gp_mission_table;

#endif /* GP_MISSION_H */
