/**
 * @file step.h
 * @brief The runtime's own step in the simulator's process (sim/cstep.py): the board
 *        binary's tick (runtime/include/gp_runtime.h) on readings handed over as the
 *        serial link hands them over, and what the simulator reports of a run.
 */
#ifndef GPS_STEP_H
#define GPS_STEP_H

#include <stddef.h>
#include <stdint.h>

#include "gp_plan.h"
#include "gp_runtime.h"

#define GPS_NOTE_LEN 256  /**< bytes of the envelope guard's words, NUL included */

/** The runtime in-process: what the board binary keeps between SENSORS frames, plus what
 *  the simulator reports (the variables each state was first entered with). */
typedef struct {
    gp_runtime runtime;
    gp_plan plan;
    gp_run_options options;
    const gp_mission *mission;              /**< &flown */
    gp_mission flown;                       /**< the tables' mission with the flight's
                                                 envelope (its vehicle's rating) */
    uint32_t suspends;                      /**< ticks after which the board slept */
    uint8_t entered[GP_MAX_STATES];         /**< the state was entered */
    double entry_vars[GP_MAX_STATES][GP_MAX_VARIABLES];  /**< its variables then */
    char envelope_note[GPS_NOTE_LEN];       /**< the guard's words on its last breach */
} gps_step;

/**
 * @brief One SENSORS frame: the values of the sensors in `mask` arrive (binary32, as on
 *        the link; the others keep their last value), then the runtime's tick.
 * @param values GP_N_SENSORS values, of which those in `mask` are read
 */
void gps_step_tick(gps_step *s, uint32_t tick, uint32_t mask, const float *values,
                   gp_command *cmd, gp_tick_report *report);

/** @brief Whether a tick's breach of the envelope hands control back (the fault action):
 *         the board binary releases the glider, the run ends. */
int gps_step_releases(const gps_step *s, const gp_tick_report *report);

#endif /* GPS_STEP_H */
