/**
 * @file gp_store.h
 * @brief What survives a crash, in the state directory: `checkpoint` (replaced
 *        atomically on every transition) and `events.log` (append-only, fsync'd).
 */
#ifndef GP_STORE_H
#define GP_STORE_H

#include <stddef.h>
#include <stdint.h>

#include "gp_machine.h"
#include "gp_mission.h"
#include "gp_runtime.h"

#define GP_PATH_MAX 1024
#define GP_CHECKPOINT_MAGIC "GPCKPT01"
/** Bytes of gp_runtime a checkpoint holds: all but the route's waypoints, which
 *  follow from the mission and are computed again on resume. */
#define GP_CHECKPOINT_STATE_SIZE (offsetof(gp_runtime, route) + offsetof(gp_route_state, waypoints))
/** magic, mission hash, state size, the state, CRC-32 */
#define GP_CHECKPOINT_SIZE (8 + 64 + 4 + GP_CHECKPOINT_STATE_SIZE + 4)

/** @brief Serialise a checkpoint into `buf` (GP_CHECKPOINT_SIZE bytes). */
void gp_checkpoint_encode(const gp_mission *mission, const gp_runtime *rt, uint8_t *buf);

/**
 * @brief Check and read a checkpoint.
 * @return NULL on success, else what is wrong (truncated, bad CRC, other mission)
 */
const char *gp_checkpoint_decode(const gp_mission *mission, const uint8_t *buf, size_t len,
                                 gp_runtime *rt);

/**
 * @brief Write `data` to dir/name: temporary file, fsync, rename, fsync of the directory.
 * @return 0, or -1 with errno set
 */
int gp_write_atomically(const char *dir, const char *name, const void *data, size_t len);

/**
 * @brief Read dir/name whole into `buf` (capacity `cap`).
 * @return bytes read, -1 if it does not exist, -2 on an error or if it is larger than cap
 */
long gp_read_file(const char *path, void *buf, size_t cap);

/** @brief Join dir and name into out (GP_PATH_MAX); @return 0, -1 if too long. */
int gp_path_join(const char *dir, const char *name, char *out);

/**
 * @brief Append one line `time_s kind from to stack_depth` to the event log and fsync.
 *        Names are the states'; "-" stands for none.
 * @param kind "start", "goto", "call", "return", "exit" or "fault"
 * @return 0, or -1 on a write error
 */
int gp_events_append(int fd, const gp_mission *mission, double time_s, const char *kind,
                     uint8_t from, uint8_t to, uint8_t depth);

/** @brief Name of a transition kind as the event log writes it. */
const char *gp_transition_name(uint8_t kind);

#endif /* GP_STORE_H */
