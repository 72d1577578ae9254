/* The tick: semantics first (which state), then schedule, pilot and route (what to fly). */
#include "gp_runtime.h"

#include <math.h>
#include <string.h>

void gp_runtime_init(gp_runtime *rt)
{
    memset(rt, 0, sizeof *rt);
    for (int i = 0; i < GP_N_SENSORS; i++) {
        rt->sensors[i] = NAN;
    }
    rt->machine.state = GP_EXITED;
    rt->profile = GP_NO_PROFILE;
}

static void enter_state(gp_runtime *rt, const gp_mission *mission)
{
    rt->entry_time_s = rt->sensors[GP_SENSOR_MISSIONTIME];
    rt->profile = GP_NO_PROFILE;
    if (rt->machine.state < mission->n_states) {
        gp_route_enter(&rt->route, &mission->states[rt->machine.state].route);
        rt->route.turn_from_rad = rt->sensors[GP_SENSOR_HEADING];
    }
}

static void record(gp_tick_report *report, gp_transition transition)
{
    report->transitions[report->n_transitions++] = transition;
}

/* Vertical and horizontal commands of the current state, held to the envelope. */
static gp_envelope_breach fly(gp_runtime *rt, const gp_mission *mission, const gp_run_options *options,
                gp_command *cmd)
{
    const gp_state *state = &mission->states[rt->machine.state];
    const gp_plan_state *ps = options->plan ? &options->plan->states[rt->machine.state] : NULL;
    gp_schedule_now now;
    gp_schedule(state, ps, rt->sensors[GP_SENSOR_MISSIONTIME] - rt->entry_time_s,
                mission->default_ballast_cc, &now);
    if (now.profile >= state->n_profiles) {
        now.profile = 0;
    }
    const gp_profile *profile = &state->profiles[now.profile];
    gp_profile_input in = {.kind = profile->kind, .plan_pitch_rad = now.pitch_rad,
                           .ballast_cc = now.ballast_cc, .naive = options->naive_tracker,
                           .plan_speed_mps = now.speed_mps,
                           .unplanned_speed_mps = mission->unplanned_speed_mps,
                           .thrust_w = isnan(now.thrust_w) ? profile->thrust_w : now.thrust_w};
    if (profile->args && profile->n_args > 0) {
        profile->args(rt->sensors, rt->machine.vars, in.args);
    }
    int entered = now.profile != rt->profile;
    if (entered) {  /* entering the state or switching alternative */
        gp_pilot_enter(&rt->pilot, &in, rt->sensors[GP_SENSOR_DEPTH],
                       rt->sensors[GP_SENSOR_ALTITUDE]);
        rt->profile = now.profile;
    }
    gp_pilot_command vertical;
    gp_pilot_step(&rt->pilot, &in, rt->sensors[GP_SENSOR_DEPTH], rt->sensors[GP_SENSOR_TEMP],
                  rt->sensors[GP_SENSOR_ALTITUDE], &vertical);
    double heading;
    int heading_valid = state->route.kind == GP_ROUTE_TURN
        ? gp_route_turn(&rt->route, &state->route,
                        rt->sensors[GP_SENSOR_MISSIONTIME] - rt->entry_time_s, &heading)
        : gp_route_step(&rt->route, &state->route, rt->sensors[GP_SENSOR_LAT],
                        rt->sensors[GP_SENSOR_LON], &heading);
    cmd->profile = now.profile;
    int holds = heading_valid && (state->route.kind == GP_ROUTE_HEADING
                                  || state->route.kind == GP_ROUTE_TURN);
    cmd->flags = (uint8_t)(vertical.flags | (heading_valid ? GP_FLAG_HEADING : 0)
                           | (holds ? GP_FLAG_HEADING_HOLD : 0));
    cmd->depth_target_m = (float)vertical.depth_target_m;
    cmd->pitch_rad = (float)vertical.pitch_rad;
    cmd->ballast_cc = (float)vertical.ballast_cc;
    cmd->heading_rad = (float)heading;
    cmd->speed_mps = (float)vertical.speed_mps;
    cmd->thrust_w = (float)vertical.thrust_w;
    cmd->sensor_power = now.sensor_power;
    int yo = profile->kind == GP_PROFILE_YO || profile->kind == GP_PROFILE_THERMOTRACKYO;
    return gp_envelope_hold(&mission->envelope, mission->max_ballast_cc, &rt->envelope, entered,
                            yo ? in.args : NULL, rt->sensors[GP_SENSOR_MISSIONTIME],
                            rt->sensors[GP_SENSOR_DEPTH], cmd);
}

/* The mission has ended on a guard: the glider surfaces and holds there. */
static void surface_and_hold(const gp_mission *mission, gp_command *cmd)
{
    cmd->flags = GP_FLAG_DONE | GP_FLAG_SURFACE | GP_FLAG_CLIMBING;
    cmd->pitch_rad = (float)GP_SURFACE_PITCH_RAD;
    cmd->ballast_cc = (float)mission->max_ballast_cc;
}

/* The transition fields of the command from the tick's last transition. */
static void name_transition(const gp_tick_report *report, gp_command *cmd)
{
    cmd->from = cmd->to = GP_NO_STATE;
    if (report->n_transitions > 0) {
        const gp_transition *last = &report->transitions[report->n_transitions - 1];
        cmd->transition = last->kind;
        cmd->from = last->from;
        cmd->to = last->to;
    }
}

void gp_runtime_tick(gp_runtime *rt, const gp_mission *mission, const gp_run_options *options,
                     uint32_t tick, gp_command *cmd, gp_tick_report *report)
{
    memset(report, 0, sizeof *report);
    memset(cmd, 0, sizeof *cmd);
    if (!rt->started) {
        gp_transition start;
        gp_machine_start(&rt->machine, mission, &start);
        rt->started = 1;
        enter_state(rt, mission);
        record(report, start);
    }
    if (rt->machine.state != GP_EXITED
        && rt->sensors[GP_SENSOR_ENERGY_LEFT] <= mission->reserve_j) {
        /* the energy guard: the battery reached its reserve. Whatever the state and the
         * stack, the mission ends here; the glider surfaces and holds there */
        record(report, (gp_transition){GP_TR_RESERVE, rt->machine.state, GP_EXITED, 0});
        rt->machine.state = GP_EXITED;
        rt->machine.depth = 0;
    } else if (rt->machine.state != GP_EXITED) {
        /* the runtime's own readings, as this tick's events see them, if they read them
         * (the distance to the waypoint costs a cosine and a square root) */
        rt->sensors[GP_SENSOR_HALFCYCLE] =
            rt->profile == GP_NO_PROFILE ? 0.0 : (double)rt->pilot.halfcycle;
        rt->sensors[GP_SENSOR_WPTREACHED] = (double)rt->route.reached;
        if (mission->own_read_mask & (1u << GP_SENSOR_WPTDIST)) {
            rt->sensors[GP_SENSOR_WPTDIST] = gp_route_distance_m(
                &rt->route, &mission->states[rt->machine.state].route,
                rt->sensors[GP_SENSOR_LAT], rt->sensors[GP_SENSOR_LON]);
        }
        uint16_t waypoint = rt->route.next;
        uint32_t reached = rt->route.reached;
        gp_transition transition;
        gp_step_result result = gp_machine_step(&rt->machine, mission, rt->sensors, &transition);
        if (result == GP_STEP_TRANSITION) {
            record(report, transition);
            if (transition.kind == GP_TR_CALL) {  /* the caller's route, for its return */
                rt->route_resume[rt->machine.depth - 1] = waypoint;
                rt->reached_resume[rt->machine.depth - 1] = reached;
            }
            if (rt->machine.state != GP_EXITED) {
                enter_state(rt, mission);
            }
            if (transition.kind == GP_TR_RETURN
                && rt->route_resume[rt->machine.depth] < rt->route.n_waypoints) {
                rt->route.next = rt->route_resume[rt->machine.depth];
                rt->route.reached = rt->reached_resume[rt->machine.depth];
            }
        } else if (result != GP_STEP_IDLE && result != GP_STEP_ASSIGNED) {
            report->fault = (uint8_t)result;
            report->refused = transition;
        }
    }
    cmd->tick = tick;
    cmd->state = rt->machine.state;
    cmd->stack_depth = rt->machine.depth;
    cmd->event_count = rt->machine.event_count;
    name_transition(report, cmd);
    if (cmd->transition == GP_TR_RESERVE) {
        surface_and_hold(mission, cmd);
    } else if (rt->machine.state == GP_EXITED) {
        cmd->flags = GP_FLAG_DONE;
    } else {
        uint8_t was_held = rt->envelope.held;
        gp_envelope_breach breach = fly(rt, mission, options, cmd);
        if (breach.limit != GP_LIMIT_NONE && (!was_held || !rt->envelope.held)) {
            report->envelope = breach;  /* logged: an end, or the first of a held stretch */
            report->envelope_state = rt->machine.state;
        }
        if (gp_envelope_ends(&mission->envelope, &breach)
            && mission->envelope.action != GP_ENVELOPE_FAULT) {
            /* the mission's abort: whatever the state and the stack, it ends here */
            record(report, (gp_transition){GP_TR_ENVELOPE, rt->machine.state, GP_EXITED, 0});
            rt->machine.state = GP_EXITED;
            rt->machine.depth = 0;
            cmd->state = GP_EXITED;
            cmd->stack_depth = 0;
            cmd->profile = 0;
            name_transition(report, cmd);
            surface_and_hold(mission, cmd);
            cmd->depth_target_m = 0;
            cmd->heading_rad = 0;
            cmd->sensor_power = 0;
        }
    }
    rt->last_command = *cmd;
    rt->has_command = 1;
}

int gp_runtime_sleeps(const gp_runtime *rt, const gp_mission *mission,
                      const gp_run_options *options)
{
    uint8_t state = rt->machine.state;
    if (state >= mission->n_states) {
        return 0;
    }
    return options->plan ? options->plan->states[state].sleep : mission->states[state].sleep;
}
