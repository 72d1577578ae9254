/**
 * @file gp_frame.h
 * @brief Frames and messages of the science-computer link (docs/protocol.md):
 *        COBS, CRC-16, header, and the payload of every message. No I/O here.
 */
#ifndef GP_FRAME_H
#define GP_FRAME_H

#include <stddef.h>
#include <stdint.h>

#include "gp_mission.h"

#define GP_MAX_PACKET (6 + GP_MAX_PAYLOAD + 2)     /**< decoded packet, 248 bytes */
#define GP_MAX_FRAME (GP_MAX_WIRE + 1)             /**< with the delimiter */

/** Why a frame was dropped (0: it was not). */
typedef enum {
    GP_FRAME_OK = 0,
    GP_FRAME_COBS,       /**< not a COBS encoding */
    GP_FRAME_TOO_LONG,   /**< more than GP_MAX_WIRE bytes before the delimiter */
    GP_FRAME_SHORT,      /**< shorter than header + CRC */
    GP_FRAME_CRC,
    GP_FRAME_VERSION,
    GP_FRAME_LENGTH,     /**< length field disagrees with the packet, or a bad payload size */
    GP_FRAME_TYPE,       /**< unknown message type */
} gp_frame_error;

typedef struct {
    uint8_t type, seq, ack;
    uint16_t length;
    uint8_t payload[GP_MAX_PAYLOAD];
} gp_frame;

/** The COMMAND message (protocol.md, 36 bytes). */
typedef struct {
    uint32_t tick;
    uint8_t state, stack_depth, transition, from, to, profile, flags;
    float depth_target_m, pitch_rad, ballast_cc, heading_rad;
    uint32_t sensor_power;
    uint32_t event_count;
} gp_command;

/** Receiver state: bytes since the last delimiter, bounded by GP_MAX_WIRE. */
typedef struct {
    uint8_t buf[GP_MAX_WIRE];
    uint16_t len;
    uint8_t overlong;
} gp_frame_reader;

/** @brief COBS-encode `len` <= GP_MAX_PACKET bytes; @return encoded length (no delimiter). */
size_t gp_cobs_encode(const uint8_t *in, size_t len, uint8_t *out);

/** @brief COBS-decode into `out` (capacity `cap`); @return decoded length or -1. */
int gp_cobs_decode(const uint8_t *in, size_t len, uint8_t *out, size_t cap);

/**
 * @brief Build a frame's wire bytes (COBS + 0x00) into `wire` (GP_MAX_FRAME bytes).
 * @return number of bytes, or 0 if the payload is too long
 */
size_t gp_frame_build(uint8_t type, uint8_t seq, uint8_t ack, const uint8_t *payload,
                      size_t len, uint8_t *wire);

/** @brief Parse a frame's COBS bytes (without the delimiter) into `out`. */
gp_frame_error gp_frame_parse(const uint8_t *wire, size_t len, gp_frame *out);

/**
 * @brief Feed bytes to the reader up to and including the next delimiter.
 * @param used bytes consumed (all of `len` if no delimiter came)
 * @return -1 if no frame ended, else a gp_frame_error for the frame the delimiter
 *         ended (GP_FRAME_OK: `out` holds it); an empty frame (two delimiters) is ignored
 */
int gp_frame_reader_feed(gp_frame_reader *reader, const uint8_t *data, size_t len,
                         size_t *used, gp_frame *out);

/** @brief Human-readable name of a frame error. */
const char *gp_frame_error_name(gp_frame_error error);

/* ---- payloads ---------------------------------------------------------------- */

/**
 * @brief Unpack SENSORS: bits of `mask` below GP_N_SENSORS update `sensors`; other
 *        bits are read and ignored.
 * @return GP_FRAME_OK or GP_FRAME_LENGTH
 */
gp_frame_error gp_sensors_unpack(const gp_frame *frame, uint32_t *tick, double *sensors);

/** @brief SENSORS payload (for tests and tools); @return payload length. */
size_t gp_sensors_pack(uint32_t tick, uint32_t mask, const double *sensors, uint8_t *payload);

size_t gp_command_pack(const gp_command *command, uint8_t *payload);
gp_frame_error gp_command_unpack(const gp_frame *frame, gp_command *command);

/** @brief HELLO payload for a mission; @return payload length. */
size_t gp_hello_pack(const gp_mission *mission, uint8_t *payload);

/** @brief PLAN payload view: offset, total and a pointer to the data inside `frame`. */
gp_frame_error gp_plan_piece_unpack(const gp_frame *frame, uint16_t *offset, uint16_t *total,
                                    const uint8_t **data, uint16_t *len);

size_t gp_plan_status_pack(int accepted, const char *message, uint8_t *payload);

#endif /* GP_FRAME_H */
