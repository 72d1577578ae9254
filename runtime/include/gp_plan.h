/**
 * @file gp_plan.h
 * @brief The plan file (docs/plan-format.md), read strictly, and the schedule it sets
 *        inside a state (docs/pilot.md): sensor power windows, profile alternation,
 *        planned pitch and ballast.
 */
#ifndef GP_PLAN_H
#define GP_PLAN_H

#include <stddef.h>
#include <stdint.h>

#include "gp_mission.h"
#include "gp_sha256.h"

#define GP_PLAN_ERROR_LEN 160

typedef struct {
    uint8_t sensor;                  /**< registry index */
    double period_s, on_s;
} gp_plan_sensor;

typedef struct {
    double share, pitch_rad, ballast_cc, speed_mps;
    double thrust_w;                 /**< a yo's thruster [W]; 0: off (the field left out) */
} gp_plan_profile;

typedef struct {
    int line;                        /**< of its `state` line in the file */
    double energy_j;                 /**< predicted, all components [J] */
    double clock_mhz;                /**< [MHz]; 0: no clock to set (`computer none`) */
    double cycle_s;
    uint8_t sleep;                   /**< 1: the board sleeps between ticks */
    double cycles_per_tick;          /**< the work the plan assumed [cycles]; 0: the runtime's */
    uint8_t n_sensors, n_profiles;
    gp_plan_sensor sensors[GP_MAX_PLAN_SENSORS];
    gp_plan_profile profiles[GP_MAX_PROFILE_ALTERNATIVES];
} gp_plan_state;

/** A plan as the runtime keeps it: what it flies. The per-state prediction and the
 *  assumptions are checked for their form and left to the simulator and to people. */
typedef struct {
    char computer[GP_MAX_NAME_LENGTH + 1];
    double clock_mhz, budget_j, predicted_j;
    uint8_t n_components;            /**< energy columns of each state's prediction */
    uint8_t n_assumptions;
    uint8_t n_states;
    uint8_t is_signed;               /**< the file ends in `seq` and `hmac` lines */
    uint32_t seq;                    /**< a signed plan's sequence number (1..), else 0 */
    uint8_t tag[GP_SHA256_SIZE];     /**< a signed plan's HMAC-SHA256 tag */
    gp_plan_state states[GP_MAX_STATES];
} gp_plan;

/** What a plan must show to be flown when the vehicle holds a key. */
typedef struct {
    uint8_t key[GP_PLAN_KEY_BYTES];  /**< provisioned on the vehicle */
    uint32_t last_seq;               /**< sequence of the plan in force, 0: none signed */
    uint8_t last_tag[GP_SHA256_SIZE];  /**< its tag */
} gp_plan_auth;

/**
 * @brief Read a plan file strictly against the compiled mission: its form, its values
 *        within the contract's bounds, the board's clocks (a plan for `computer none`,
 *        clocks 0, flies on any build), with a key its signature, and then
 *        `gp_plan_check`.
 * @param auth NULL: no key; a signed plan's tag is read but not checked. Else the plan
 *             must be signed with auth->key, with a sequence number above auth->last_seq
 *             or, to send the plan in force again, equal to it with the same tag.
 * @param out  filled only on success
 * @param error on failure: "line N: what is wrong" (NUL-terminated, GP_PLAN_ERROR_LEN)
 * @return 0 accepted, -1 rejected
 */
int gp_plan_read(const char *text, size_t len, const gp_mission *mission,
                 const gp_plan_auth *auth, gp_plan *out, char error[GP_PLAN_ERROR_LEN]);

/**
 * @brief Hold a plan read from its file to its mission (contract/plan_check.py, rule for
 *        rule and message for message): the board, the budget against the battery, the
 *        prediction against the budget, each state's duties against the mission's bounds,
 *        its pitch, ballast and speed against the vehicle's flight model.
 * @param error on failure: "line N: what is wrong" (NUL-terminated, GP_PLAN_ERROR_LEN)
 * @return 0 the plan may fly, -1 it contradicts its mission
 */
int gp_plan_check(const gp_plan *plan, const gp_mission *mission,
                  char error[GP_PLAN_ERROR_LEN]);

/** What the schedule sets at time `t_in_s` in a state. */
typedef struct {
    uint8_t profile;            /**< alternative flown */
    uint32_t sensor_power;      /**< bit i: power sensor i */
    double pitch_rad;           /**< planned pitch, NaN: the profile's own */
    double ballast_cc;          /**< B */
    double speed_mps;           /**< planned speed [m/s], NaN: no plan */
    double thrust_w;            /**< planned thrust [W], NaN: no plan */
} gp_schedule_now;

/**
 * @brief The schedule of `state` (plan entry `ps`, NULL without a plan) at `t_in_s`
 *        seconds after entry.
 */
void gp_schedule(const gp_state *state, const gp_plan_state *ps, double t_in_s,
                 double default_ballast_cc, gp_schedule_now *out);

#endif /* GP_PLAN_H */
