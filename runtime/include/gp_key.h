/**
 * @file gp_key.h
 * @brief The plan key provisioned on the vehicle (`--key FILE`, written by
 *        `gliderplan keygen`): 64 lowercase hex digits and a LF, readable by its owner only.
 */
#ifndef GP_KEY_H
#define GP_KEY_H

#include <stddef.h>
#include <stdint.h>

#include "gp_contract.h"

/** Bytes of a key file: the key in hex and a LF. */
#define GP_KEY_FILE_BYTES (2 * GP_PLAN_KEY_BYTES + 1)

/**
 * @brief Read a key file.
 * @param error on failure: what is wrong, naming the file (capacity `cap`)
 * @return 0, or -1 (no such file, unreadable, readable by group or others, not a key)
 */
int gp_key_load(const char *path, uint8_t key[GP_PLAN_KEY_BYTES], char *error, size_t cap);

#endif /* GP_KEY_H */
