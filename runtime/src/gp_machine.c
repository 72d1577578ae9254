/* The event system: one step fires at most one event (language/semantics.py). */
#include "gp_machine.h"

#include <string.h>

#include "gp_envelope.h"

static int known_action(uint8_t action)
{
    return action == GP_ACT_NONE || (action >= GP_ACT_GOTO && action <= GP_ACT_EXIT);
}

void gp_machine_start(gp_machine *m, const gp_mission *mission, gp_transition *out)
{
    memset(m, 0, sizeof *m);
    for (int i = 0; i < mission->n_vars && i < GP_MAX_VARIABLES; i++) {
        m->vars[i] = mission->var_initial[i];
    }
    m->state = 0;
    out->kind = GP_TR_START;
    out->from = GP_EXITED;
    out->to = 0;
    out->depth = 0;
}

int gp_machine_fired_event(const gp_machine *m, const gp_mission *mission,
                           const double *sensors)
{
    if (m->state >= mission->n_states) {
        return -1;
    }
    const gp_state *state = &mission->states[m->state];
    for (int i = 0; i < state->n_events; i++) {
        if (state->events[i].condition(sensors, m->vars)) {
            return i;
        }
    }
    return -1;
}

gp_step_result gp_machine_step(gp_machine *m, const gp_mission *mission,
                               const double *sensors, gp_transition *out)
{
    int index = gp_machine_fired_event(m, mission, sensors);
    if (index < 0) {
        return GP_STEP_IDLE;
    }
    const gp_event *event = &mission->states[m->state].events[index];
    uint8_t here = m->state;
    *out = (gp_transition){event->action, here, event->target, m->depth};
    /* Refuse before touching anything, as the reference raises before returning. */
    if ((event->action == GP_ACT_GOTO || event->action == GP_ACT_CALL)
        && event->target >= mission->n_states) {
        return GP_STEP_BAD_TABLE;
    }
    if (event->action == GP_ACT_CALL
        && (m->depth >= mission->stack_depth || m->depth >= GP_MAX_STACK_DEPTH)) {
        return GP_STEP_OVERFLOW;
    }
    if (event->action == GP_ACT_RETURN && m->depth == 0) {
        out->to = GP_EXITED;
        return GP_STEP_UNDERFLOW;
    }
    if (!known_action(event->action)) {
        return GP_STEP_BAD_TABLE;
    }
    if (event->assign) {
        event->assign(sensors, m->vars);
    }
    m->event_count++;
    switch (event->action) {
    case GP_ACT_GOTO:
        m->depth = 0;
        m->state = event->target;
        break;
    case GP_ACT_CALL:
        m->stack[m->depth++] = here;
        m->state = event->target;
        break;
    case GP_ACT_RETURN:
        m->state = m->stack[--m->depth];
        break;
    case GP_ACT_EXIT:
        m->depth = 0;
        m->state = GP_EXITED;
        break;
    default:
        return GP_STEP_ASSIGNED;
    }
    out->to = m->state;
    out->depth = m->depth;
    return GP_STEP_TRANSITION;
}

const char *gp_mission_check(const gp_mission *mission)
{
    if (mission->n_states < 1 || mission->n_states > GP_MAX_STATES || mission->states == NULL) {
        return "state count outside 1..GP_MAX_STATES";
    }
    if (mission->n_vars > GP_MAX_VARIABLES || (mission->n_vars > 0 && !mission->var_initial)) {
        return "more variables than GP_MAX_VARIABLES, or no initial values";
    }
    if (mission->stack_depth < 1 || mission->stack_depth > GP_MAX_STACK_DEPTH) {
        return "stack depth outside 1..GP_MAX_STACK_DEPTH";
    }
    if (!(mission->reserve_j >= 0) || !(mission->max_ballast_cc >= 0)
        || !(mission->unplanned_speed_mps >= 0) || mission->n_clocks < 1
        || mission->n_clocks > GP_MAX_BOARD_CLOCKS || !mission->clocks_mhz) {
        return "no pump volume or energy reserve, or a clock count outside 1..GP_MAX_BOARD_CLOCKS";
    }
    const char *envelope_problem = gp_envelope_check(&mission->envelope);
    if (envelope_problem) {
        return envelope_problem;
    }
    for (int s = 0; s < mission->n_states; s++) {
        const gp_state *state = &mission->states[s];
        if (state->n_profiles < 1 || state->n_profiles > GP_MAX_PROFILE_ALTERNATIVES
            || !state->profiles) {
            return "profile count outside 1..GP_MAX_PROFILE_ALTERNATIVES";
        }
        if (state->unplanned_profile >= state->n_profiles) {
            return "the profile flown without a plan is not one of the state's";
        }
        for (int p = 0; p < state->n_profiles; p++) {
            const gp_profile *profile = &state->profiles[p];
            if (profile->n_args > GP_MAX_PROFILE_ARGS || (profile->n_args > 0 && !profile->args)) {
                return "more profile arguments than GP_MAX_PROFILE_ARGS, or no function for them";
            }
        }
        if (state->route.n_points > GP_MAX_ROUTE_POINTS
            || (state->route.n_points > 0 && !state->route.points)) {
            return "more route points than GP_MAX_ROUTE_POINTS, or none given";
        }
        uint32_t sensor_mask = 0;
        for (int i = 0; i < state->n_sensors; i++) {
            if (!state->sensors || state->sensors[i] >= GP_N_SENSORS) {
                return "sensor index outside the sensor array";
            }
            sensor_mask |= 1u << state->sensors[i];
        }
        if (sensor_mask != state->sensor_mask) {
            return "sensor mask disagrees with the sensor list";
        }
        for (int i = 0; i < state->n_events; i++) {
            const gp_event *event = state->events ? &state->events[i] : NULL;
            if (!event || !event->condition || !known_action(event->action)
                || ((event->action == GP_ACT_GOTO || event->action == GP_ACT_CALL)
                    && event->target >= mission->n_states)) {
                return "an event without a condition, or with an unknown action or target";
            }
        }
    }
    return NULL;
}
