/**
 * @file gp_runtime.h
 * @brief One tick of the mission: the event system, the plan's schedule, the pilot
 *        and the route together turn one SENSORS reading into one COMMAND.
 *        No I/O: the link (gp_link.h) feeds it and stores what it reports.
 */
#ifndef GP_RUNTIME_H
#define GP_RUNTIME_H

#include <stdint.h>

#include "gp_envelope.h"
#include "gp_frame.h"
#include "gp_machine.h"
#include "gp_mission.h"
#include "gp_pilot.h"
#include "gp_plan.h"
#include "gp_route.h"

#define GP_NO_PROFILE 0xFFu

/** Everything a restarted runtime needs to resume: the checkpoint's content. */
typedef struct {
    gp_machine machine;
    double sensors[GP_N_SENSORS];   /**< last value of each sensor, NaN before the first */
    double entry_time_s;            /**< missiontime at the last entry into the state */
    uint8_t started;
    uint8_t profile;                /**< alternative flown, GP_NO_PROFILE: enter on next tick */
    uint8_t has_command;            /**< last_command is valid */
    uint32_t events_log_bytes;      /**< size of the event log once this state was reached */
    gp_pilot pilot;
    gp_envelope_memory envelope;    /**< the envelope guard's memory of the profile's turns */
    gp_command last_command;        /**< the last tick answered (resent for the same tick) */
    uint16_t route_resume[GP_MAX_STACK_DEPTH];  /**< per call on the stack: the caller's waypoint */
    uint32_t reached_resume[GP_MAX_STACK_DEPTH];  /**< and the waypoints it had reached */
    gp_route_state route;           /**< last: its waypoints are not checkpointed */
} gp_runtime;

/** What happened in one tick, for the event log. */
typedef struct {
    /** start, an event and the envelope guard's end can share tick 0 */
    gp_transition transitions[3];
    uint8_t n_transitions;
    uint8_t fault;                  /**< gp_step_result of a refused event, 0: none */
    gp_transition refused;          /**< the refused transition when `fault` */
    gp_envelope_breach envelope;    /**< a command outside the envelope (limit 0: none) */
    uint8_t envelope_state;         /**< the state that commanded it */
} gp_tick_report;

/** Options of a run. */
typedef struct {
    const gp_plan *plan;            /**< NULL: no plan */
    uint8_t naive_tracker;
} gp_run_options;

/** @brief A runtime before its first tick (sensors NaN). */
void gp_runtime_init(gp_runtime *rt);

/**
 * @brief One tick on `rt->sensors` (already updated from SENSORS).
 * @param cmd the COMMAND answering tick `tick` (also kept in rt->last_command)
 */
void gp_runtime_tick(gp_runtime *rt, const gp_mission *mission, const gp_run_options *options,
                     uint32_t tick, gp_command *cmd, gp_tick_report *report);

/**
 * @brief Whether the board sleeps after answering the last tick: the state flown sleeps
 *        between ticks (the plan's SLEEP, without a plan the mission's `computer sleep
 *        between ticks`); never once the mission has ended.
 */
int gp_runtime_sleeps(const gp_runtime *rt, const gp_mission *mission,
                      const gp_run_options *options);

#endif /* GP_RUNTIME_H */
