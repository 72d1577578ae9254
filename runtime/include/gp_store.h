/**
 * @file gp_store.h
 * @brief What survives a crash, in the state directory: `checkpoint` (a record of what
 *        a resumed runtime needs, written in place to alternate slots, and a journal of
 *        the readings stepped since) and `events.log` (append-only, fsync'd).
 *
 * The checkpoint file: a header (magic, mission hash, slot size, journal size, CRC-32) in
 * its first GP_CHECKPOINT_SLOT_BYTES, two slots of that size, then the journal
 * (GP_JOURNAL_BYTES, reserved when the file is created). A record holds only what is in
 * use (the stack to its depth, the mission's variables, the sensors it reads, the
 * tracker's window to its length): ~170 bytes for Fig. 2 against 2.0 KiB for the whole
 * runtime state. Record n goes to slot n mod 2, so the newest intact record is never
 * overwritten: a write torn by a crash or a power loss leaves the record before it,
 * which the CRC-32 tells apart. The file is created whole (temporary file, rename)
 * holding the state before the first tick, so there is always an intact record.
 *
 * A tick that needs no record appends an entry to the journal instead: the payload of
 * the SENSORS frame it stepped, which is all a resumed runtime needs to step that tick
 * again (the runtime is a function of its state and the readings). An entry names the
 * record it follows (its sequence number) and ends in two Fletcher sums over its 32-bit
 * words; the first entry that is torn, damaged, or of another record ends the journal.
 * A new record empties the journal: it holds all the entries said.
 */
#ifndef GP_STORE_H
#define GP_STORE_H

#include <stddef.h>
#include <stdint.h>

#include "gp_machine.h"
#include "gp_mission.h"
#include "gp_runtime.h"

#define GP_PATH_MAX 1024
#define GP_CHECKPOINT_MAGIC "GPCKPT07"
/** The envelope guard's figures a checkpoint keeps (gp_envelope_memory's doubles). */
#define GP_ENVELOPE_MEMORY_FIGURES 6
/** Header to first slot, slot to slot: a flash page, so a torn write stays in its slot. */
#define GP_CHECKPOINT_SLOT_BYTES 4096
/** The journal after the slots: four flash pages, 341 Fig. 2 ticks between records. */
#define GP_JOURNAL_BYTES (4 * GP_CHECKPOINT_SLOT_BYTES)
/** magic, mission hash (hex), slot size, journal size, CRC-32 */
#define GP_CHECKPOINT_HEADER_BYTES (8 + 64 + 4 + 4 + 4)
/** The largest journal entry: record number, length, payload (to whole words), sums. */
#define GP_JOURNAL_MAX_ENTRY (4 + 4 + (GP_MAX_PAYLOAD + 3) / 4 * 4 + 8)
/** The largest record: every count at its bound. */
#define GP_CHECKPOINT_MAX_RECORD                                                         \
    (4 + 2                                     /* sequence number, length */             \
     + 6 + 7 * GP_MAX_STACK_DEPTH + 4 + 4 + 8  /* flags and counts, stack and its    */ \
                                               /* routes, events, log, entry           */ \
     + 8 * GP_MAX_VARIABLES + 8 * GP_N_SENSORS                                           \
     + 4 + 4 + 8 * 3 + 8 * 3 + 16 * GP_TRACK_WINDOW  /* pilot */                         \
     + 2 + 4 + 8                               /* route: waypoint, reached, turn from */ \
     + 5 + 8 * GP_ENVELOPE_MEMORY_FIGURES      /* envelope: flags, figures */            \
     + 1 + GP_COMMAND_MAX_SIZE                 /* last COMMAND */                        \
     + 4)                                      /* CRC-32 */

/** The checkpoint file of a run, open from start-up to exit. */
typedef struct {
    int fd;              /**< -1: none */
    uint32_t seq;        /**< sequence number of the newest record */
    uint32_t journal_at; /**< [bytes] of the journal in use: where the next entry goes */
} gp_checkpoint;

/**
 * @brief Open dir/checkpoint and load its newest intact record into `rt`; if the file
 *        does not exist, create it holding `rt` as it is (the state before the first tick).
 * @param resumed set to 1 if a file was there, 0 if it was created
 * @param problem on failure, what is wrong (damaged, another mission, a system error)
 * @return 0, or -1
 */
int gp_checkpoint_open(gp_checkpoint *cp, const char *dir, const gp_mission *mission,
                       gp_runtime *rt, int *resumed, const char **problem);

/**
 * @brief After gp_checkpoint_open: the next payload the journal holds after the record
 *        loaded, into `payload` (GP_MAX_PAYLOAD bytes). Read them all before the first
 *        append: an append goes where reading stopped, over a torn entry if any.
 * @return the payload's length, or -1 after the last intact entry
 */
long gp_journal_next(gp_checkpoint *cp, uint8_t *payload);

/**
 * @brief Append `payload` (at most GP_MAX_PAYLOAD bytes) to the journal and wait for the
 *        disk (fdatasync).
 * @return 0, 1 if the journal has no room for it (write a record instead), or -1 with
 *         errno set
 */
int gp_journal_append(gp_checkpoint *cp, const uint8_t *payload, size_t len);

/**
 * @brief Write `rt` as the next record, over the older slot, and wait for the disk
 *        (fdatasync); the journal starts afresh after it.
 * @return 0, or -1 with errno set
 */
int gp_checkpoint_store(gp_checkpoint *cp, const gp_mission *mission, const gp_runtime *rt);

/** @brief Close the file (no-op without one). */
void gp_checkpoint_close(gp_checkpoint *cp);

/**
 * @brief Encode `rt` as record `seq` into `record` (GP_CHECKPOINT_MAX_RECORD bytes).
 * @return the record's length
 */
size_t gp_checkpoint_encode(const gp_mission *mission, const gp_runtime *rt, uint32_t seq,
                            uint8_t *record);

/**
 * @brief Check and read one record: the bytes of a slot, `len` of them at most (the
 *        record's own length field says where it ends).
 * @return NULL on success (`rt` and `seq` set), else what is wrong
 */
const char *gp_checkpoint_decode(const gp_mission *mission, const uint8_t *record, size_t len,
                                 uint32_t *seq, gp_runtime *rt);

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
