/* The safety envelope (docs/pilot.md, The envelope): the last word on every COMMAND. */
#include "gp_envelope.h"

#include <math.h>
#include <stdio.h>

#define PI 3.14159265358979323846
#define HOUR_S 3600.0

/* A range's edges: from zero up, finite, the low no higher than the high. */
static int is_range(double low, double high)
{
    return low >= 0 && low <= high && isfinite(high);
}

const char *gp_envelope_check(const gp_envelope *envelope)
{
    if (!(envelope->max_depth_m > 0) || !(envelope->max_pitch_rad > 0)
        || !(envelope->max_pitch_rad < asin(1.0)) || !(envelope->min_yo_band_m >= 0)
        || !(envelope->min_yo_band_m < envelope->max_depth_m)
        || !(envelope->min_inflection_s >= 0) || envelope->action > GP_ENVELOPE_CLAMP) {
        return "no envelope: a depth, pitch, band, inflection time or action out of range";
    }
    if (!is_range(envelope->min_speed_mps, envelope->max_speed_mps)
        || !is_range(envelope->min_thrust_w, envelope->max_thrust_w)
        || !(envelope->max_turn_rate_rad_s > 0) || !(envelope->max_pump_power_w > 0)
        || !isfinite(envelope->pump_out_j_per_cc) || !isfinite(envelope->pump_out_j_per_cc_m)
        || !isfinite(envelope->pump_in_j_per_cc) || !isfinite(envelope->pump_in_j_per_cc_m)) {
        return "no envelope: a speed, thrust, turn rate or pump figure out of range";
    }
    return NULL;
}

static gp_envelope_breach breach(uint8_t limit, double value, double bound)
{
    return (gp_envelope_breach){limit, value, bound};
}

/* A speed or a thruster's power: 0 (off), or within [low, high]. */
static int within(double value, double low, double high)
{
    return value == 0.0 || (value >= low && value <= high);
}

/* The edge of {0} and [low, high] nearest `value` (which is not NaN). */
static float edge(double value, double low, double high)
{
    return (float)(value < 0.0 ? 0.0 : value < low ? low : high);
}

/* The first of depth, pitch, pumped volume, speed and thrust outside its range; NaN is
 * outside. With the clamp action, each is held at its edge (a NaN is not: it has no side). */
static gp_envelope_breach hold_values(const gp_envelope *envelope, double max_ballast_cc,
                                      gp_command *cmd)
{
    gp_envelope_breach first = breach(GP_LIMIT_NONE, 0, 0);
    double depth = cmd->depth_target_m, pitch = cmd->pitch_rad, ballast = cmd->ballast_cc;
    double speed = cmd->speed_mps, thrust = cmd->thrust_w;
    int clamp = envelope->action == GP_ENVELOPE_CLAMP;
    if (!(depth >= 0 && depth <= envelope->max_depth_m)) {
        first = breach(GP_LIMIT_DEPTH, depth, envelope->max_depth_m);
        if (clamp && !isnan(depth)) {
            cmd->depth_target_m = (float)(depth < 0 ? 0.0 : envelope->max_depth_m);
        }
    }
    if (!(fabs(pitch) <= envelope->max_pitch_rad)) {
        first = first.limit ? first : breach(GP_LIMIT_PITCH, pitch, envelope->max_pitch_rad);
        if (clamp && !isnan(pitch)) {
            cmd->pitch_rad = (float)copysign(envelope->max_pitch_rad, pitch);
        }
    }
    if (!(fabs(ballast) <= max_ballast_cc)) {
        first = first.limit ? first : breach(GP_LIMIT_BALLAST, ballast, max_ballast_cc);
        if (clamp && !isnan(ballast)) {
            cmd->ballast_cc = (float)copysign(max_ballast_cc, ballast);
        }
    }
    double low = envelope->min_speed_mps, high = envelope->max_speed_mps;
    if (!within(speed, low, high)) {
        first = first.limit ? first : breach(GP_LIMIT_SPEED, speed, speed > high ? high : low);
        if (clamp && !isnan(speed)) {
            cmd->speed_mps = edge(speed, low, high);
        }
    }
    low = envelope->min_thrust_w, high = envelope->max_thrust_w;
    if (!within(thrust, low, high)) {
        first = first.limit ? first : breach(GP_LIMIT_THRUST, thrust, thrust > high ? high : low);
        if (clamp && !isnan(thrust)) {
            cmd->thrust_w = edge(thrust, low, high);
        }
    }
    return first;
}

/* The heading turns at most at the rated rate: whatever the route asks (a waypoint behind,
 * a state with another route), the command turns toward it by no more than the vehicle
 * turns in the time since the last command, and gets there. Under every action: a turn
 * is flown, never refused, so it is no breach. */
static void hold_turn(const gp_envelope *envelope, gp_envelope_memory *memory, double time_s,
                      gp_command *cmd)
{
    double heading = cmd->heading_rad;
    if (!(cmd->flags & GP_FLAG_HEADING) || !isfinite(heading)) {
        memory->headed = 0;  /* no heading flown: the next one is taken as it is */
        return;
    }
    if (memory->headed) {
        double most = envelope->max_turn_rate_rad_s * (time_s - memory->heading_s);
        double turn = heading - memory->heading_rad;
        turn = turn > PI ? turn - 2.0 * PI : turn < -PI ? turn + 2.0 * PI : turn;
        if (fabs(turn) > most) {  /* NaN (an infinite rate, no time since): any turn */
            heading = memory->heading_rad + copysign(most > 0.0 ? most : 0.0, turn);
            heading = heading < 0.0 ? heading + 2.0 * PI : heading >= 2.0 * PI ? heading - 2.0 * PI
                                                                                : heading;
            cmd->heading_rad = (float)heading;
            heading = cmd->heading_rad;
        }
    }
    memory->headed = 1;
    memory->heading_rad = heading;
    memory->heading_s = time_s;
}

/* The pump's energy as a bucket paid back at the rated mean power: a volume moved out at
 * depth z costs (a + b z) per cc, moved in max(0, a + b z); more than an hour's worth
 * outstanding is a breach (it ends the flight, whatever the action). */
static gp_envelope_breach hold_pump(const gp_envelope *envelope, gp_envelope_memory *memory,
                                    double time_s, double depth_m, const gp_command *cmd)
{
    double ballast = cmd->ballast_cc;
    if (!isfinite(ballast)) {
        return breach(GP_LIMIT_NONE, 0, 0);  /* the pumped volume's own limit says so */
    }
    if (memory->pumped) {
        double z = depth_m > 0.0 ? depth_m : 0.0;  /* NaN: no reading, the surface */
        double moved = ballast - memory->ballast_cc;
        const gp_envelope *e = envelope;
        double per_cc = moved > 0.0 ? e->pump_out_j_per_cc + e->pump_out_j_per_cc_m * z
                                    : e->pump_in_j_per_cc + e->pump_in_j_per_cc_m * z;
        double owed = memory->pump_j - envelope->max_pump_power_w * (time_s - memory->pump_s);
        memory->pump_j = (owed > 0.0 ? owed : 0.0) + (per_cc > 0.0 ? per_cc * fabs(moved) : 0.0);
    }
    memory->pumped = 1;
    memory->ballast_cc = ballast;
    memory->pump_s = time_s;
    double hour_j = envelope->max_pump_power_w * HOUR_S;
    return memory->pump_j > hour_j ? breach(GP_LIMIT_PUMP_ENERGY, memory->pump_j, hour_j)
                                   : breach(GP_LIMIT_NONE, 0, 0);
}

gp_envelope_breach gp_envelope_hold(const gp_envelope *envelope, double max_ballast_cc,
                                    gp_envelope_memory *memory, int entered,
                                    const double *yo_band, double time_s, double depth_m,
                                    gp_command *cmd)
{
    gp_envelope_breach found = breach(GP_LIMIT_NONE, 0, 0);
    if (yo_band) {  /* both ends, whichever leg is flown: a variable may have moved either */
        double lo = yo_band[0], hi = yo_band[1];
        if (!(lo >= 0 && lo <= envelope->max_depth_m)) {
            found = breach(GP_LIMIT_DEPTH, lo, envelope->max_depth_m);
        } else if (!(hi >= 0 && hi <= envelope->max_depth_m)) {
            found = breach(GP_LIMIT_DEPTH, hi, envelope->max_depth_m);
        } else if (!(hi - lo >= envelope->min_yo_band_m)) {
            found = breach(GP_LIMIT_BAND, hi - lo, envelope->min_yo_band_m);
        }
    }
    gp_envelope_breach values = hold_values(envelope, max_ballast_cc, cmd);
    found = found.limit ? found : values;
    uint8_t climbing = (cmd->flags & GP_FLAG_CLIMBING) != 0;
    if (entered) {
        memory->turned = 0;
    } else if (yo_band && climbing != memory->climbing) {  /* the yo turned */
        double since = time_s - memory->last_turn_s;
        /* thrashing ends the flight even where a held value let it go on */
        if (memory->turned && !(since >= envelope->min_inflection_s)
            && !gp_envelope_ends(envelope, &found)) {
            found = breach(GP_LIMIT_INFLECTION, since, envelope->min_inflection_s);
        }
        memory->turned = 1;
        memory->last_turn_s = time_s;
    }
    memory->climbing = climbing;
    hold_turn(envelope, memory, time_s, cmd);
    gp_envelope_breach pump = hold_pump(envelope, memory, time_s, depth_m, cmd);
    if (pump.limit && !gp_envelope_ends(envelope, &found)) {  /* as thrashing, it ends */
        found = pump;
    }
    memory->held = found.limit != GP_LIMIT_NONE && !gp_envelope_ends(envelope, &found);
    if (memory->held) {
        cmd->flags |= GP_FLAG_ENVELOPE;
    }
    return found;
}

int gp_envelope_ends(const gp_envelope *envelope, const gp_envelope_breach *found)
{
    if (found->limit == GP_LIMIT_NONE) {
        return 0;
    }
    return envelope->action != GP_ENVELOPE_CLAMP || found->limit == GP_LIMIT_BAND
           || found->limit == GP_LIMIT_INFLECTION || found->limit == GP_LIMIT_PUMP_ENERGY
           || isnan(found->value);
}

const char *gp_envelope_limit_name(uint8_t limit)
{
    switch (limit) {
    case GP_LIMIT_DEPTH: return "depth";
    case GP_LIMIT_PITCH: return "pitch";
    case GP_LIMIT_BALLAST: return "pumped volume";
    case GP_LIMIT_BAND: return "yo band";
    case GP_LIMIT_INFLECTION: return "time between inflections";
    case GP_LIMIT_SPEED: return "speed";
    case GP_LIMIT_THRUST: return "thruster power";
    case GP_LIMIT_PUMP_ENERGY: return "pump energy within an hour";
    default: return "none";
    }
}

const char *gp_envelope_limit_unit(uint8_t limit)
{
    switch (limit) {
    case GP_LIMIT_PITCH: return "rad";
    case GP_LIMIT_BALLAST: return "cc";
    case GP_LIMIT_INFLECTION: return "s";
    case GP_LIMIT_SPEED: return "m/s";
    case GP_LIMIT_THRUST: return "W";
    case GP_LIMIT_PUMP_ENERGY: return "J";
    default: return "m";
    }
}

void gp_envelope_say(const gp_envelope *envelope, const gp_envelope_breach *found,
                     double time_s, const char *state, char *out, size_t len)
{
    const char *what = !gp_envelope_ends(envelope, found)         ? "held at the limit"
                       : envelope->action == GP_ENVELOPE_FAULT ? "releasing control"
                                                               : "the mission ends, surfacing";
    const char *unit = gp_envelope_limit_unit(found->limit);
    double value = isnan(found->value) ? fabs(found->value) : found->value;  /* "nan", signless */
    snprintf(out, len, "envelope: missiontime %g s, state %.64s: %s %g %s beyond the vehicle's "
             "%g %s; %s", time_s, state, gp_envelope_limit_name(found->limit), value, unit,
             found->bound, unit, what);
}
