/* The safety envelope (docs/pilot.md, The envelope): the last word on every COMMAND. */
#include "gp_envelope.h"

#include <math.h>
#include <stdio.h>

const char *gp_envelope_check(const gp_envelope *envelope)
{
    if (!(envelope->max_depth_m > 0) || !(envelope->max_pitch_rad > 0)
        || !(envelope->max_pitch_rad < asin(1.0)) || !(envelope->min_yo_band_m >= 0)
        || !(envelope->min_yo_band_m < envelope->max_depth_m)
        || !(envelope->min_inflection_s >= 0) || envelope->action > GP_ENVELOPE_CLAMP) {
        return "no envelope: a depth, pitch, band, inflection time or action out of range";
    }
    return NULL;
}

static gp_envelope_breach breach(uint8_t limit, double value, double bound)
{
    return (gp_envelope_breach){limit, value, bound};
}

/* The first of depth, pitch and pumped volume outside its range; NaN is outside. With the
 * clamp action, each is held at its edge (a NaN is not: it has no side). */
static gp_envelope_breach hold_values(const gp_envelope *envelope, double max_ballast_cc,
                                      gp_command *cmd)
{
    gp_envelope_breach first = breach(GP_LIMIT_NONE, 0, 0);
    double depth = cmd->depth_target_m, pitch = cmd->pitch_rad, ballast = cmd->ballast_cc;
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
    return first;
}

gp_envelope_breach gp_envelope_hold(const gp_envelope *envelope, double max_ballast_cc,
                                    gp_envelope_memory *memory, int entered,
                                    const double *yo_band, double time_s, gp_command *cmd)
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
           || found->limit == GP_LIMIT_INFLECTION || isnan(found->value);
}

const char *gp_envelope_limit_name(uint8_t limit)
{
    switch (limit) {
    case GP_LIMIT_DEPTH: return "depth";
    case GP_LIMIT_PITCH: return "pitch";
    case GP_LIMIT_BALLAST: return "pumped volume";
    case GP_LIMIT_BAND: return "yo band";
    case GP_LIMIT_INFLECTION: return "time between inflections";
    default: return "none";
    }
}

const char *gp_envelope_limit_unit(uint8_t limit)
{
    switch (limit) {
    case GP_LIMIT_PITCH: return "rad";
    case GP_LIMIT_BALLAST: return "cc";
    case GP_LIMIT_INFLECTION: return "s";
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
