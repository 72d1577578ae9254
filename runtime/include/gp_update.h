/**
 * @file gp_update.h
 * @brief Plan updates (docs/plan-update.md): a signed binary delta against the plan in
 *        force, at most one short Iridium message (GP_MAX_UPDATE_BYTES). Checked in this
 *        order: a key, the form, the tag, a plan in force, the sequence numbers, the plan
 *        it was made against; then the changes are made in the plan file's text, its
 *        checksum written anew and the result signed with the vehicle's key, checked
 *        against the hash the update names, and read strictly like any plan.
 *        No I/O and no allocation: the caller stores and adopts the new plan.
 */
#ifndef GP_UPDATE_H
#define GP_UPDATE_H

#include <stddef.h>
#include <stdint.h>

#include "gp_contract.h"
#include "gp_mission.h"
#include "gp_plan.h"

/** Bytes of a verdict's message, its NUL included (it travels in UPDATE_STATUS). */
#define GP_UPDATE_MESSAGE_LEN 224

/** The largest number of changes an update may hold (its count is a u8). */
#define GP_UPDATE_MAX_CHANGES 255

/**
 * @brief Apply the update `update` (`len` bytes) to the signed plan file in force.
 * @param held      the plan file in force, `held_len` bytes (NULL or 0: none)
 * @param auth      NULL: no key is provisioned (every update is refused); else the key
 *                  and the plan in force's sequence number and tag
 * @param mission   the compiled mission the new plan is read against
 * @param out       GP_MAX_PLAN_BYTES bytes: the new plan file (on GP_UPDATE_APPLIED)
 * @param out_len   its length, set once it is made (also when it is then refused)
 * @param plan      the new plan, read strictly (on GP_UPDATE_APPLIED); untouched otherwise
 * @param message   what became of the update, NUL-terminated: "ok: plan N in force" or why
 *                  it was refused (the same words as gliderplan.planner.update)
 * @return a gp_update_status: GP_UPDATE_APPLIED, GP_UPDATE_DUPLICATE (nothing to do),
 *         or why the update is refused (the plan in force stays)
 */
gp_update_status gp_update_apply(const uint8_t *update, size_t len, const char *held,
                                 size_t held_len, const gp_plan_auth *auth,
                                 const gp_mission *mission, char *out, size_t *out_len,
                                 gp_plan *plan, char message[GP_UPDATE_MESSAGE_LEN]);

/**
 * @brief The plan-file NUMBER of mantissa x 10^exponent, as docs/plan-update.md writes it.
 * @param text at least 48 bytes
 * @return its length
 */
size_t gp_update_decimal_text(int64_t mantissa, int exponent, char *text);

#endif /* GP_UPDATE_H */
