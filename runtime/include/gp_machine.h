/**
 * @file gp_machine.h
 * @brief The event system of the paper's Fig. 3: the current state's events checked
 *        in order each tick, a bounded state stack, variables. Semantics equal
 *        language/semantics.py.
 */
#ifndef GP_MACHINE_H
#define GP_MACHINE_H

#include <stdint.h>

#include "gp_mission.h"

#define GP_EXITED GP_NO_STATE  /**< `state` once the mission exited */

typedef struct {
    uint8_t kind;   /**< gp_transition_kind */
    uint8_t from;   /**< state index, GP_EXITED for none (start) */
    uint8_t to;     /**< state index, GP_EXITED for none (exit) */
    uint8_t depth;  /**< stack depth after the transition */
} gp_transition;

/** Outcome of one step. */
typedef enum {
    GP_STEP_IDLE = 0,        /**< no event fired */
    GP_STEP_ASSIGNED,        /**< an event without action fired: variables changed */
    GP_STEP_TRANSITION,      /**< an event with an action fired */
    GP_STEP_OVERFLOW,        /**< refused: call past the mission's stack depth */
    GP_STEP_UNDERFLOW,       /**< refused: return with an empty stack */
    GP_STEP_BAD_TABLE,       /**< refused: event targets a state that does not exist */
} gp_step_result;

typedef struct {
    uint8_t state;                    /**< current state, GP_EXITED once exited */
    uint8_t depth;                    /**< states on the stack */
    uint8_t stack[GP_MAX_STACK_DEPTH];      /**< callers, stack[depth-1] on top */
    double vars[GP_MAX_VARIABLES];
    uint32_t event_count;             /**< events fired (transitions and assignments) */
} gp_machine;

/** @brief Enter the start state with the initial variables; `out` is the start transition. */
void gp_machine_start(gp_machine *m, const gp_mission *mission, gp_transition *out);

/** @brief Index of the first event of the current state whose condition holds, or -1. */
int gp_machine_fired_event(const gp_machine *m, const gp_mission *mission,
                           const double *sensors);

/**
 * @brief One tick: fire the first true event (assignments in order, then its action).
 *        A refused event (overflow, underflow, bad table) changes nothing.
 * @param out the transition when GP_STEP_TRANSITION; the refused one on a fault
 */
gp_step_result gp_machine_step(gp_machine *m, const gp_mission *mission,
                               const double *sensors, gp_transition *out);

/** @brief Check a mission table against the runtime's limits; @return NULL or what is wrong. */
const char *gp_mission_check(const gp_mission *mission);

#endif /* GP_MACHINE_H */
