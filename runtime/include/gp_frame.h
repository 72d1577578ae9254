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
/** Where a payload is put in a wire buffer for gp_frame_seal: after the room for the
 *  first COBS code byte and the 6-byte header. */
#define GP_FRAME_PAYLOAD_AT 7

/** Why a frame was dropped (0: it was not). */
typedef enum {
    GP_FRAME_OK = 0,
    GP_FRAME_COBS,       /**< not a COBS encoding */
    GP_FRAME_TOO_LONG,   /**< more than GP_MAX_WIRE bytes before the delimiter */
    GP_FRAME_SHORT,      /**< shorter than header + CRC */
    GP_FRAME_CRC,
    GP_FRAME_VERSION,
    GP_FRAME_LENGTH,     /**< length field disagrees with the packet, or a bad payload */
    GP_FRAME_TYPE,       /**< unknown message type */
    GP_FRAME_BASE,       /**< a COMMAND update whose base the receiver does not hold */
} gp_frame_error;

/** A decoded frame; its payload lies in the buffer it was decoded in (no copy). */
typedef struct {
    uint8_t type, seq, ack;
    uint16_t length;
    const uint8_t *payload;
} gp_frame;

/** The COMMAND message whole (protocol.md); on the wire it travels as the fields that
 *  differ from a base COMMAND. */
typedef struct {
    uint32_t tick;
    uint8_t state, stack_depth, transition, from, to, profile, flags;
    float depth_target_m, pitch_rad, ballast_cc, heading_rad;
    uint32_t sensor_power;
    uint32_t event_count;
    float speed_mps, thrust_w;   /**< propelled flight [m/s], a yo's thruster [W]; 0: none */
} gp_command;

/** Receiver state: bytes since the last delimiter, bounded by GP_MAX_WIRE. */
typedef struct {
    uint8_t buf[GP_MAX_WIRE];
    uint16_t len;
    uint8_t overlong;
} gp_frame_reader;

/**
 * @brief COBS-encode in place: `buf[1..len]` is the packet (len <= GP_MAX_PACKET),
 *        `buf[0]` is room for the first code byte; each zero becomes a code byte, and
 *        the delimiter (0) goes to `buf[len + 1]`.
 * @return the encoded length, len + 1 (without the delimiter)
 */
size_t gp_cobs_encode(uint8_t *buf, size_t len);

/**
 * @brief COBS-decode in place: afterwards `buf[1..]` holds the packet (each code byte
 *        but the first becomes the zero it stands for; nothing moves).
 * @return the packet's length, or -1 (a zero byte, a block past the end, or a block of
 *         254 bytes, which no packet of GP_MAX_PACKET bytes has)
 */
int gp_cobs_decode(uint8_t *buf, size_t len);

/**
 * @brief Frame a payload that lies at `wire + GP_FRAME_PAYLOAD_AT`: header, CRC-16,
 *        COBS in place and the delimiter (`wire` holds GP_MAX_FRAME bytes).
 * @return the frame's length with its delimiter, or 0 if the payload is too long
 */
size_t gp_frame_seal(uint8_t *wire, uint8_t type, uint8_t seq, uint8_t ack, size_t len);

/** @brief gp_frame_seal of a payload copied in from `payload`. */
size_t gp_frame_build(uint8_t type, uint8_t seq, uint8_t ack, const uint8_t *payload,
                      size_t len, uint8_t *wire);

/** @brief Parse a frame's COBS bytes (without the delimiter), decoding them in place. */
gp_frame_error gp_frame_parse(uint8_t *wire, size_t len, gp_frame *out);

/**
 * @brief Feed bytes to the reader up to and including the next delimiter. A frame that
 *        lies whole in `data` is decoded there, in place; one that came in pieces, in
 *        the reader's buffer. Either way `out->payload` points into that memory.
 * @param used bytes consumed (all of `len` if no delimiter came)
 * @return -1 if no frame ended, else a gp_frame_error for the frame the delimiter
 *         ended (GP_FRAME_OK: `out` holds it); an empty frame (two delimiters) is ignored
 */
int gp_frame_reader_feed(gp_frame_reader *reader, uint8_t *data, size_t len, size_t *used,
                         gp_frame *out);

/** @brief Human-readable name of a frame error. */
const char *gp_frame_error_name(gp_frame_error error);

/* ---- payloads ---------------------------------------------------------------- */

/**
 * @brief Unpack SENSORS: bits of its mask (`read_mask` when the frame carries none)
 *        below GP_N_SENSORS update `sensors`; other bits are read and ignored.
 * @param flags the frame's GP_SENSORS_* flags
 * @return GP_FRAME_OK, or GP_FRAME_LENGTH (a size that disagrees with the mask, a
 *         reserved flag)
 */
gp_frame_error gp_sensors_unpack(const gp_frame *frame, uint32_t read_mask, uint32_t *tick,
                                 uint8_t *flags, double *sensors);

/** @brief SENSORS payload (for tests and tools): the mask is left out when it is
 *         `read_mask`; @return payload length. */
size_t gp_sensors_pack(uint32_t tick, uint8_t flags, uint32_t mask, uint32_t read_mask,
                       const double *sensors, uint8_t *payload);

/**
 * @brief COMMAND payload: the fields of `command` that differ from `base`, which it
 *        names by how many ticks back it lies (1..255); NULL, or a base outside that
 *        range, sends it whole (the fields that differ from the zero COMMAND).
 * @return payload length, at most GP_COMMAND_MAX_SIZE
 */
size_t gp_command_pack(const gp_command *command, const gp_command *base, uint8_t *payload);

/**
 * @brief Apply a COMMAND payload to the base it names: the zero COMMAND, or `base`
 *        (the COMMAND the receiver holds; NULL: none).
 * @return GP_FRAME_OK, GP_FRAME_LENGTH, or GP_FRAME_BASE if it names another base
 */
gp_frame_error gp_command_unpack(const gp_frame *frame, const gp_command *base,
                                 gp_command *command);

/** @brief HELLO payload for a mission; @return payload length. */
size_t gp_hello_pack(const gp_mission *mission, uint8_t *payload);

/** @brief PLAN (or PLAN_UPDATE: the same pieces) payload view: offset, total and a pointer
 *  to the data inside `frame`. */
gp_frame_error gp_plan_piece_unpack(const gp_frame *frame, uint16_t *offset, uint16_t *total,
                                    const uint8_t **data, uint16_t *len);

size_t gp_plan_status_pack(int accepted, const char *message, uint8_t *payload);

/** @brief UPDATE_STATUS payload: `status` (gp_update_status), the sequence number of the
 *  plan in force after the update, the message (cut to the payload); @return its length. */
size_t gp_update_status_pack(uint8_t status, uint32_t seq, const char *message,
                             uint8_t *payload);

#endif /* GP_FRAME_H */
