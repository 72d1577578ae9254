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

/** The runtime in-process: what the board binary keeps between SENSORS frames, plus what
 *  the simulator reports (the variables each state was first entered with). */
typedef struct {
    gp_runtime runtime;
    gp_plan plan;
    gp_run_options options;
    const gp_mission *mission;
    uint32_t suspends;                      /**< ticks after which the board slept */
    uint8_t entered[GP_MAX_STATES];         /**< the state was entered */
    double entry_vars[GP_MAX_STATES][GP_MAX_VARIABLES];  /**< its variables then */
} gps_step;

/**
 * @brief One SENSORS frame: the values of the sensors in `mask` arrive (binary32, as on
 *        the link; the others keep their last value), then the runtime's tick.
 * @param values GP_N_SENSORS values, of which those in `mask` are read
 */
void gps_step_tick(gps_step *s, uint32_t tick, uint32_t mask, const float *values,
                   gp_command *cmd, gp_tick_report *report);

#endif /* GPS_STEP_H */
