/* The simulator's C side: the runtime's own step, in this process.
 *
 * A shared library of the runtime's step sources (runtime/src: the tick, the event
 * system, the pilot, the routes, the plan reader), this file and the flight loop
 * (flight.c), built once and cached (sim/cstep.py); a mission's tables
 * (language/codegen_c.py) come in another shared object, by the address of their
 * gp_mission. The context is allocated by the caller (gps_step_size bytes); nothing here
 * allocates, reads or writes a file. */
#include "step.h"

#include <stdio.h>
#include <string.h>

#include "gp_machine.h"
#include "gp_update.h"

size_t gps_step_size(void)
{
    return sizeof(gps_step);
}

/**
 * @brief A runtime before its first tick, for `mission` held to `envelope` (a flight's
 *        vehicle's rating: a scenario's drawn vehicle flies the same tables, compiled
 *        once), flying the plan `plan_text` (`plan_len` bytes; NULL: none), read by the
 *        runtime's own reader.
 * @param error what is wrong with the mission's tables, the envelope or the plan
 *        (GP_PLAN_ERROR_LEN)
 * @return 0, or -1 with `error` set
 */
int gps_step_init(gps_step *s, const gp_mission *mission, const gp_envelope *envelope,
                  const char *plan_text, size_t plan_len, int naive_tracker, char *error)
{
    memset(s, 0, sizeof *s);
    s->flown = *mission;
    s->flown.envelope = *envelope;
    s->mission = &s->flown;
    const char *wrong = gp_mission_check(s->mission);
    if (wrong) {
        snprintf(error, GP_PLAN_ERROR_LEN, "%s", wrong);
        return -1;
    }
    if (plan_text && gp_plan_read(plan_text, plan_len, s->mission, NULL, &s->plan, error) < 0) {
        return -1;
    }
    gp_runtime_init(&s->runtime);
    s->options = (gp_run_options){plan_text ? &s->plan : NULL, (uint8_t)(naive_tracker != 0)};
    return 0;
}

/* The variables of each state entered for the first time this tick: the start state's
 * are the initial values (an event of tick 0 may assign after it was entered). */
static void note_entries(gps_step *s, const gp_tick_report *report)
{
    const gp_machine *m = &s->runtime.machine;
    for (int i = 0; i < report->n_transitions; i++) {
        uint8_t to = report->transitions[i].to;
        if (to >= s->mission->n_states || s->entered[to]) {
            continue;
        }
        s->entered[to] = 1;
        for (int v = 0; v < s->mission->n_vars; v++) {
            s->entry_vars[to][v] = report->transitions[i].kind == GP_TR_START
                                       ? s->mission->var_initial[v] : m->vars[v];
        }
    }
}

void gps_step_tick(gps_step *s, uint32_t tick, uint32_t mask, const float *values,
                   gp_command *cmd, gp_tick_report *report)
{
    for (int i = 0; i < GP_N_SENSORS; i++) {
        if (mask >> i & 1u) {
            s->runtime.sensors[i] = (double)values[i];
        }
    }
    gp_runtime_tick(&s->runtime, s->mission, &s->options, tick, cmd, report);
    note_entries(s, report);
    if (report->envelope.limit != GP_LIMIT_NONE) {
        gp_envelope_say(&s->mission->envelope, &report->envelope,
                        s->runtime.sensors[GP_SENSOR_MISSIONTIME],
                        s->mission->states[report->envelope_state].name, s->envelope_note,
                        sizeof s->envelope_note);
    }
    if (!report->fault && !gps_step_releases(s, report)) {  /* a refused event ends the run: the board never sleeps on */
        s->suspends += (uint32_t)gp_runtime_sleeps(&s->runtime, s->mission, &s->options);
    }
}

int gps_step_releases(const gps_step *s, const gp_tick_report *report)
{
    return gp_envelope_ends(&s->mission->envelope, &report->envelope)
           && s->mission->envelope.action == GP_ENVELOPE_FAULT;
}

/**
 * @brief A plan update received at the surface (docs/plan-update.md), applied by the
 *        runtime's own gp_update_apply against the plan file in force `held` (`held_len`
 *        bytes) with the vehicle's `key`, as the board binary applies one from its link:
 *        on GP_UPDATE_APPLIED the new plan is flown from the next tick and its file is in
 *        `out` (GP_MAX_PLAN_BYTES bytes, `*out_len`).
 * @param message what became of it (GP_UPDATE_MESSAGE_LEN bytes)
 * @return a gp_update_status
 */
int gps_step_update(gps_step *s, const uint8_t *update, size_t len, const char *held,
                    size_t held_len, const uint8_t *key, char *out, size_t *out_len,
                    char *message)
{
    gp_plan_auth auth = {.last_seq = s->options.plan ? s->plan.seq : 0};
    memcpy(auth.key, key, sizeof auth.key);
    if (s->options.plan) {
        memcpy(auth.last_tag, s->plan.tag, sizeof auth.last_tag);
    }
    gp_plan plan;
    gp_update_status status = gp_update_apply(update, len, held_len ? held : NULL, held_len,
                                              &auth, s->mission, out, out_len, &plan, message);
    if (status == GP_UPDATE_APPLIED) {
        s->plan = plan;
        s->options.plan = &s->plan;
    }
    return (int)status;
}

/** @brief The envelope guard's words on its last breach, into `out` (GPS_NOTE_LEN). */
void gps_step_envelope_note(const gps_step *s, char *out)
{
    memcpy(out, s->envelope_note, sizeof s->envelope_note);
}

/* ---- what the runtime holds ------------------------------------------------------ */

/** @brief Events fired so far (transitions and assignments). */
uint32_t gps_step_events(const gps_step *s)
{
    return s->runtime.machine.event_count;
}

/** @brief The sequence number of the plan in force (0: none, or unsigned). */
uint32_t gps_step_plan_seq(const gps_step *s)
{
    return s->options.plan ? s->plan.seq : 0;
}

/** @brief Ticks after which the board slept until the next frame. */
uint32_t gps_step_suspends(const gps_step *s)
{
    return s->suspends;
}

/** @brief The mission's variables now, into `out` (GP_MAX_VARIABLES values). */
void gps_step_variables(const gps_step *s, double *out)
{
    memcpy(out, s->runtime.machine.vars, sizeof s->runtime.machine.vars);
}

/** @brief Whether `state` was entered; if so its variables then, into `out`. */
int gps_step_entered(const gps_step *s, int state, double *out)
{
    if (state < 0 || state >= GP_MAX_STATES || !s->entered[state]) {
        return 0;
    }
    memcpy(out, s->entry_vars[state], sizeof s->entry_vars[state]);
    return 1;
}

/** @brief The runtime's own readings as the last tick's events saw them: halfcycle,
 *         wptdist (NaN unless the mission reads it), wptreached. */
void gps_step_own_readings(const gps_step *s, double *out)
{
    out[0] = s->runtime.sensors[GP_SENSOR_HALFCYCLE];
    out[1] = s->runtime.sensors[GP_SENSOR_WPTDIST];
    out[2] = s->runtime.sensors[GP_SENSOR_WPTREACHED];
}

