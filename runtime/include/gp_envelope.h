/**
 * @file gp_envelope.h
 * @brief The safety envelope (docs/pilot.md, The envelope): every COMMAND the tick
 *        computed is held to the vehicle's rating, whatever the events computed. The
 *        limits come from the vehicle file through the compiled mission
 *        (`gp_mission.envelope`, a gp_envelope). Pure: no I/O.
 */
#ifndef GP_ENVELOPE_H
#define GP_ENVELOPE_H

#include <stddef.h>
#include <stdint.h>

#include "gp_frame.h"
#include "gp_mission.h"

/** What the guard remembers between ticks (checkpointed with the runtime). */
typedef struct {
    double last_turn_s;          /**< missiontime of the profile's last turn [s] */
    double heading_rad;          /**< the last heading commanded [rad] */
    double heading_s;            /**< missiontime it was commanded [s] */
    double ballast_cc;           /**< the last volume commanded [cc] */
    double pump_s;               /**< missiontime of the last command [s] */
    double pump_j;               /**< the pump's energy not yet paid back at the rated mean
                                      power: above an hour's worth, it works too hard [J] */
    uint8_t turned;              /**< last_turn_s is valid: the profile turned once */
    uint8_t climbing;            /**< the last command climbed */
    uint8_t held;                /**< the last command was held (clamped) */
    uint8_t headed;              /**< heading_rad is valid: the last command had a heading */
    uint8_t pumped;              /**< ballast_cc and pump_s are valid: a command was sent */
} gp_envelope_memory;

/** A limit broken by one command. */
typedef struct {
    uint8_t limit;               /**< gp_envelope_limit, GP_LIMIT_NONE: within */
    double value;                /**< the value commanded (gp_envelope_limit_unit) */
    double bound;                /**< the limit it broke, same unit */
} gp_envelope_breach;

/** @brief NULL, or what makes `envelope` no envelope (a compiled mission's check). */
const char *gp_envelope_check(const gp_envelope *envelope);

/**
 * @brief Hold one tick's command to the envelope.
 * @param max_ballast_cc the pump's volume either side of neutral [cc]
 * @param entered 1 on the first tick of a profile (its turns start afresh)
 * @param yo_band the yo's (min, max) depth arguments [m]; NULL: not a yo
 * @param time_s the tick's missiontime [s]
 * @param depth_m the depth reading [m], where the pump works (NaN: at the surface)
 * @param cmd the command: clamped (and GP_FLAG_ENVELOPE set) when the action is clamp
 *        and the limit can be held at an edge; its heading turned from the last at most
 *        at the rated turn rate, under every action
 * @return the first limit broken (GP_LIMIT_NONE: none); with the clamp action a depth,
 *         pitch, ballast, speed or thrust breach has been held, a band, inflection or
 *         pump-energy one has not
 */
gp_envelope_breach gp_envelope_hold(const gp_envelope *envelope, double max_ballast_cc,
                                    gp_envelope_memory *memory, int entered,
                                    const double *yo_band, double time_s, double depth_m,
                                    gp_command *cmd);

/** @brief Whether a breach ends the mission (fault or surface), rather than being held. */
int gp_envelope_ends(const gp_envelope *envelope, const gp_envelope_breach *breach);

/** @brief The name of a limit ("depth", "pitch", ...), for the log and messages. */
const char *gp_envelope_limit_name(uint8_t limit);

/** @brief The unit of a limit's value and bound ("m", "rad", "cc", "s", "m/s", ...). */
const char *gp_envelope_limit_unit(uint8_t limit);

/**
 * @brief What the guard did, in words (stderr's and the simulator's `envelope:` line):
 *        the missiontime [s], the state, the limit, the value and the bound, and whether
 *        the command was held, control released or the mission ended.
 * @param out `len` bytes, NUL-terminated (cut to fit)
 */
void gp_envelope_say(const gp_envelope *envelope, const gp_envelope_breach *found,
                     double time_s, const char *state, char *out, size_t len);

#endif /* GP_ENVELOPE_H */
