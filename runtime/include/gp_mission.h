/**
 * @file gp_mission.h
 * @brief The compiled mission: constant tables the code generator emits
 *        (language/codegen_c.py) and the runtime executes.
 *
 * One generated C file defines `gp_mission_table` and the functions it points to.
 * Everything is `const` and static: the runtime allocates nothing.
 * Sensor indices and the limits of the tables are those of gp_contract.h.
 */
#ifndef GP_MISSION_H
#define GP_MISSION_H

#include <stdint.h>

#include "gp_contract.h"

/* The tables count in uint8_t: the contract's limits must fit. */
_Static_assert(GP_MAX_STATES <= UINT8_MAX && GP_MAX_VARIABLES <= UINT8_MAX
               && GP_MAX_STACK_DEPTH <= UINT8_MAX && GP_MAX_EVENTS_PER_STATE <= UINT8_MAX
               && GP_MAX_PROFILE_ALTERNATIVES <= UINT8_MAX && GP_MAX_PROFILE_ARGS <= UINT8_MAX
               && GP_MAX_ROUTE_POINTS <= UINT8_MAX && GP_N_SENSORS <= UINT8_MAX,
               "a limit of gp_contract.h does not fit the mission tables' uint8_t counts");
_Static_assert(GP_N_SENSORS <= 32, "sensor masks are uint32_t");

/** Action of an event: the transition it makes. */
typedef enum {
    GP_ACT_NONE = GP_TR_NONE,   /**< assignments only, no transition */
    GP_ACT_GOTO = GP_TR_GOTO,
    GP_ACT_CALL = GP_TR_CALL,
    GP_ACT_RETURN = GP_TR_RETURN,
    GP_ACT_EXIT = GP_TR_EXIT,
} gp_action;

typedef enum {
    GP_PROFILE_YO = 0,
    GP_PROFILE_THERMOTRACKYO = 1,
    GP_PROFILE_SURFACE = 2,
    GP_PROFILE_HOVER = 3,
    GP_PROFILE_CRUISE = 4,       /**< level at a depth on the propeller */
    GP_PROFILE_ALTITUDE = 5,     /**< level at a height above the sea floor on the propeller */
} gp_profile_kind;

typedef enum {
    GP_ROUTE_NAV = 0,
    GP_ROUTE_NOHEADING = 1,
    GP_ROUTE_WAYPOINTS = 2,
    GP_ROUTE_SWEEP = 3,
    GP_ROUTE_GOTO_LIST = 4,
    GP_ROUTE_HEADING = 5,        /**< a compass heading held, uncorrected for the current */
    GP_ROUTE_TURN = 6,           /**< a steady turn from the heading at entry (a spiral) */
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
    gp_args_fn args;       /**< fills n_args values [m, rad, degC as the registry says];
                                a propelled profile's speed written `auto` is left out */
    double thrust_w;       /**< `thrust` on a yo: the commanded power [W]; 0: none or auto */
} gp_profile;

typedef struct {
    uint8_t kind;          /**< gp_route_kind */
    uint8_t n_points;
    double param;          /**< sweep: line spacing [m]; goto_list: radius [m];
                                heading: the heading held [rad];
                                turn: the turn rate [rad/s], positive clockwise; else unused */
    const double (*points)[2];  /**< (lat, lon) DDMM.MMMM; nav has one point */
} gp_route;

typedef struct {
    const char *name;
    gp_route route;
    const gp_profile *profiles;  /**< alternatives, in source order */
    uint8_t n_profiles;          /**< 1..GP_MAX_PROFILE_ALTERNATIVES */
    const uint8_t *sensors;      /**< sensor indices the state logs, in source order */
    uint8_t n_sensors;
    const gp_event *events;      /**< checked in order each tick; the first true fires */
    uint8_t n_events;
    double clock_mhz;            /**< `computer clock`: the state's clock [MHz]; 0: none */
    uint8_t sleep;               /**< `computer sleep between ticks`: 1, else 0 */
    uint32_t sensor_mask;        /**< `sensors` as a mask (bit i: sensor i), which the
                                      schedule powers each tick */
    uint8_t unplanned_profile;   /**< flown without a plan: the first the vehicle can fly */
} gp_state;

/** A sensor's duty bounds in one state (`contract.FlightLimits.duty_bounds`). */
typedef struct {
    uint8_t sensor;               /**< registry index */
    double low, high;             /**< [1] the least and the most duty the mission allows */
} gp_duty_bound;

/** What a plan may ask of one state beyond the contract's bounds. */
typedef struct {
    const gp_duty_bound *duties;  /**< the state's sensors with a device, in its order */
    uint8_t n_duties;
    const double *min_ballast_cc; /**< per profile alternative: a plan's ballast exceeds it [cc] */
} gp_state_bounds;

/** The figures of the mission, vehicle and board a plan is held to (`gp_plan_check`, the
 *  mirror of contract/plan_check.py; `contract.FlightLimits`). */
typedef struct {
    const char *board;            /**< the board a plan names (or "none" for any) */
    double max_budget_j;          /**< the battery less its reserve [J] */
    double min_pitch_rad, max_pitch_rad;  /**< commanded pitch, open range [rad] */
    double max_speed_mps;         /**< the vehicle's fastest glide [m/s] */
    double min_propelled_mps, max_propelled_mps;  /**< a level profile's speeds [m/s] */
    double min_thrust_w, max_thrust_w;  /**< a yo's thruster command, where on [W] */
    const gp_state_bounds *states;  /**< one per state */
} gp_plan_bounds;

/** The vehicle's rating every command is held to (contract.Envelope, gp_envelope.h). */
typedef struct {
    double max_depth_m;          /**< deepest depth target or yo end [m] */
    double max_pitch_rad;        /**< largest |pitch| [rad] */
    double min_yo_band_m;        /**< thinnest yo band [m] */
    double min_inflection_s;     /**< shortest time between two turns of a yo [s] */
    double min_speed_mps, max_speed_mps;  /**< a propelled speed: 0 (off) or within [m/s] */
    double min_thrust_w, max_thrust_w;    /**< a thruster's command: 0 (off) or within [W] */
    double max_turn_rate_rad_s;  /**< the fastest the vehicle turns [rad/s]; INFINITY: any */
    double max_pump_power_w;     /**< the pump's mean power over an hour [W]; INFINITY: any */
    double pump_out_j_per_cc, pump_out_j_per_cc_m;  /**< pumping out at z: (a + b z) [J/cc] */
    double pump_in_j_per_cc, pump_in_j_per_cc_m;    /**< pumping in: max(0, a + b z) [J/cc] */
    uint8_t action;              /**< gp_envelope_action */
} gp_envelope;

typedef struct {
    const char *name;
    const char *hash;             /**< CheckedMission.hash, 64 lowercase hex digits */
    const gp_state *states;       /**< states[0] is the start state */
    uint8_t n_states;
    const double *var_initial;    /**< initial values of the variables */
    uint8_t n_vars;
    uint8_t stack_depth;          /**< 1..GP_MAX_STACK_DEPTH */
    uint32_t read_mask;           /**< sensors the mission reads (bit i: sensor i) */
    uint32_t own_read_mask;       /**< the runtime's own readings it reads (halfcycle,
                                       wptdist, wptreached): it computes wptdist only then */
    double default_ballast_cc;    /**< pumped volume when no plan sets one [cc] */
    double max_ballast_cc;        /**< the vehicle's pump: most a plan may set [cc]; 0:
                                       none (a propeller AUV) */
    double unplanned_speed_mps;   /**< a propelled profile's `auto` speed without a plan
                                       [m/s]; 0: no propulsion */
    double reserve_j;             /**< energy left at which the guard ends the mission [J] */
    gp_envelope envelope;         /**< the vehicle's rating, held every tick */
    const double *clocks_mhz;     /**< the clocks of the board it flies on [MHz]; {0}:
                                       no board (`computer none`), no clock to set */
    uint8_t n_clocks;             /**< 1..GP_MAX_BOARD_CLOCKS */
    const char *const *sensor_names;  /**< GP_N_SENSORS names, registry order */
    const gp_plan_bounds *bounds; /**< NULL: a plan is held to the contract's bounds only */
} gp_mission;

/** The mission this binary was compiled for (defined by the generated file). */
extern const gp_mission gp_mission_table;

#endif /* GP_MISSION_H */
