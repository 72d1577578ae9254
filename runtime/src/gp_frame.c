/* Framing and message payloads of docs/protocol.md. Every loop is bounded by a
 * buffer size; any byte sequence yields a frame or an error, never a crash. */
#include "gp_frame.h"

#include <string.h>

#include "gp_crc.h"

static void put_u16(uint8_t *p, uint16_t v) { p[0] = (uint8_t)v; p[1] = (uint8_t)(v >> 8); }

static void put_u32(uint8_t *p, uint32_t v)
{
    for (int i = 0; i < 4; i++) {
        p[i] = (uint8_t)(v >> (8 * i));
    }
}

static uint16_t get_u16(const uint8_t *p) { return (uint16_t)(p[0] | (p[1] << 8)); }

static uint32_t get_u32(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}

static void put_f32(uint8_t *p, float v)
{
    uint32_t bits;
    memcpy(&bits, &v, sizeof bits);
    put_u32(p, bits);
}

static float get_f32(const uint8_t *p)
{
    uint32_t bits = get_u32(p);
    float v;
    memcpy(&v, &bits, sizeof v);
    return v;
}

/* Byte loops over pointers: a packet's zeros (small integers, floats) make blocks
 * short, so a memchr/memcpy per block would cost more than it saves. */
size_t gp_cobs_encode(const uint8_t *in, size_t len, uint8_t *out)
{
    uint8_t *code_at = out, *dst = out + 1;
    uint8_t code = 1;
    for (const uint8_t *p = in, *end = in + len; p < end; p++) {
        if (*p != 0) {
            *dst++ = *p;
            if (++code != 0xFF) {
                continue;
            }
        }
        *code_at = code;  /* a zero, or a full block of 254 bytes, ends the block */
        code_at = dst++;
        code = 1;
    }
    *code_at = code;
    return (size_t)(dst - out);
}

int gp_cobs_decode(const uint8_t *in, size_t len, uint8_t *out, size_t cap)
{
    const uint8_t *p = in, *end = in + len;
    uint8_t *dst = out, *dst_end = out + cap;
    while (p < end) {
        size_t code = *p++;
        if (code == 0 || code - 1 > (size_t)(end - p) || code - 1 > (size_t)(dst_end - dst)) {
            return -1;
        }
        for (const uint8_t *block_end = p + code - 1; p < block_end; p++) {
            if (*p == 0) {
                return -1;
            }
            *dst++ = *p;
        }
        if (code != 0xFF && p < end) {
            if (dst == dst_end) {
                return -1;
            }
            *dst++ = 0;
        }
    }
    return (int)(dst - out);
}

size_t gp_frame_build(uint8_t type, uint8_t seq, uint8_t ack, const uint8_t *payload,
                      size_t len, uint8_t *wire)
{
    uint8_t packet[GP_MAX_PACKET];
    if (len > GP_MAX_PAYLOAD) {
        return 0;
    }
    packet[0] = GP_PROTOCOL_VERSION;
    packet[1] = type;
    packet[2] = seq;
    packet[3] = ack;
    put_u16(packet + 4, (uint16_t)len);
    if (len > 0) {
        memcpy(packet + 6, payload, len);
    }
    uint16_t crc = gp_crc16(packet, 6 + len);
    packet[6 + len] = (uint8_t)(crc >> 8);
    packet[7 + len] = (uint8_t)crc;
    size_t n = gp_cobs_encode(packet, 8 + len, wire);
    wire[n] = 0;
    return n + 1;
}

static int known_type(uint8_t type)
{
    return type == GP_MSG_HELLO || type == GP_MSG_SENSORS || type == GP_MSG_COMMAND
        || type == GP_MSG_RELEASE || type == GP_MSG_PLAN || type == GP_MSG_PLAN_STATUS
        || type == GP_MSG_NAK;
}

gp_frame_error gp_frame_parse(const uint8_t *wire, size_t len, gp_frame *out)
{
    uint8_t packet[GP_MAX_PACKET];
    if (len > GP_MAX_WIRE) {
        return GP_FRAME_TOO_LONG;
    }
    int n = gp_cobs_decode(wire, len, packet, sizeof packet);
    if (n < 0) {
        return GP_FRAME_COBS;
    }
    if (n < 8) {
        return GP_FRAME_SHORT;
    }
    uint16_t crc = (uint16_t)((packet[n - 2] << 8) | packet[n - 1]);
    if (gp_crc16(packet, (size_t)n - 2) != crc) {
        return GP_FRAME_CRC;
    }
    if (packet[0] != GP_PROTOCOL_VERSION) {
        return GP_FRAME_VERSION;
    }
    uint16_t length = get_u16(packet + 4);
    if (length > GP_MAX_PAYLOAD || (int)length + 8 != n) {
        return GP_FRAME_LENGTH;
    }
    if (!known_type(packet[1])) {
        return GP_FRAME_TYPE;
    }
    out->type = packet[1];
    out->seq = packet[2];
    out->ack = packet[3];
    out->length = length;
    memcpy(out->payload, packet + 6, length);
    return GP_FRAME_OK;
}

int gp_frame_reader_feed(gp_frame_reader *reader, const uint8_t *data, size_t len,
                         size_t *used, gp_frame *out)
{
    const uint8_t *zero = memchr(data, 0, len);
    size_t run = zero ? (size_t)(zero - data) : len;
    size_t room = GP_MAX_WIRE - reader->len;
    if (run > room) {
        reader->overlong = 1;
    }
    memcpy(reader->buf + reader->len, data, run < room ? run : room);
    reader->len = (uint16_t)(reader->len + (run < room ? run : room));
    if (!zero) {
        *used = len;
        return -1;
    }
    *used = run + 1;
    int result;
    if (reader->overlong) {
        result = GP_FRAME_TOO_LONG;
    } else if (reader->len == 0) {
        result = -1;
    } else {
        result = gp_frame_parse(reader->buf, reader->len, out);
    }
    reader->len = 0;
    reader->overlong = 0;
    return result;
}

const char *gp_frame_error_name(gp_frame_error error)
{
    switch (error) {
    case GP_FRAME_OK: return "ok";
    case GP_FRAME_COBS: return "bad COBS";
    case GP_FRAME_TOO_LONG: return "frame too long";
    case GP_FRAME_SHORT: return "frame too short";
    case GP_FRAME_CRC: return "bad CRC";
    case GP_FRAME_VERSION: return "wrong version";
    case GP_FRAME_LENGTH: return "bad length";
    case GP_FRAME_TYPE: return "unknown type";
    }
    return "?";
}

/* ---- payloads ---------------------------------------------------------------- */

gp_frame_error gp_sensors_unpack(const gp_frame *frame, uint32_t *tick, double *sensors)
{
    if (frame->type != GP_MSG_SENSORS || frame->length < 8) {
        return GP_FRAME_LENGTH;
    }
    uint32_t mask = get_u32(frame->payload + 4);
    unsigned count = 0;
    for (uint32_t m = mask; m != 0; m &= m - 1) {  /* one round per set bit */
        count++;
    }
    if (frame->length != 8 + 4 * count) {
        return GP_FRAME_LENGTH;
    }
    *tick = get_u32(frame->payload);
    const uint8_t *p = frame->payload + 8;
    for (int i = 0; i < 32 && (mask >> i) != 0; i++) {
        if ((mask >> i) & 1u) {
            if (i < GP_N_SENSORS) {
                sensors[i] = (double)get_f32(p);
            }
            p += 4;
        }
    }
    return GP_FRAME_OK;
}

size_t gp_sensors_pack(uint32_t tick, uint32_t mask, const double *sensors, uint8_t *payload)
{
    put_u32(payload, tick);
    put_u32(payload + 4, mask);
    size_t n = 8;
    for (int i = 0; i < GP_N_SENSORS; i++) {
        if ((mask >> i) & 1u) {
            put_f32(payload + n, (float)sensors[i]);
            n += 4;
        }
    }
    return n;
}

size_t gp_command_pack(const gp_command *c, uint8_t *p)
{
    put_u32(p, c->tick);
    p[4] = c->state;
    p[5] = c->stack_depth;
    p[6] = c->transition;
    p[7] = c->from;
    p[8] = c->to;
    p[9] = c->profile;
    p[10] = c->flags;
    p[11] = 0;
    put_f32(p + 12, c->depth_target_m);
    put_f32(p + 16, c->pitch_rad);
    put_f32(p + 20, c->ballast_cc);
    put_f32(p + 24, c->heading_rad);
    put_u32(p + 28, c->sensor_power);
    put_u32(p + 32, c->event_count);
    return GP_COMMAND_SIZE;
}

gp_frame_error gp_command_unpack(const gp_frame *frame, gp_command *c)
{
    const uint8_t *p = frame->payload;
    if (frame->type != GP_MSG_COMMAND || frame->length != GP_COMMAND_SIZE) {
        return GP_FRAME_LENGTH;
    }
    c->tick = get_u32(p);
    c->state = p[4];
    c->stack_depth = p[5];
    c->transition = p[6];
    c->from = p[7];
    c->to = p[8];
    c->profile = p[9];
    c->flags = p[10];
    c->depth_target_m = get_f32(p + 12);
    c->pitch_rad = get_f32(p + 16);
    c->ballast_cc = get_f32(p + 20);
    c->heading_rad = get_f32(p + 24);
    c->sensor_power = get_u32(p + 28);
    c->event_count = get_u32(p + 32);
    return GP_FRAME_OK;
}

static int hex_digit(char c)
{
    if (c >= '0' && c <= '9') {
        return c - '0';
    }
    if (c >= 'a' && c <= 'f') {
        return c - 'a' + 10;
    }
    return -1;
}

size_t gp_hello_pack(const gp_mission *mission, uint8_t *p)
{
    p[0] = GP_PROTOCOL_VERSION;
    p[1] = GP_N_SENSORS;
    put_u32(p + 2, mission->read_mask);
    const char *hash = mission->hash;
    for (int i = 0; i < 32; i++) {
        int hi = hash ? hex_digit(hash[2 * i]) : -1;
        int lo = hi >= 0 ? hex_digit(hash[2 * i + 1]) : -1;
        p[6 + i] = (hi < 0 || lo < 0) ? 0 : (uint8_t)(hi * 16 + lo);
    }
    size_t name_len = mission->name ? strlen(mission->name) : 0;
    if (name_len > GP_MAX_PAYLOAD - 39) {
        name_len = GP_MAX_PAYLOAD - 39;
    }
    p[38] = (uint8_t)name_len;
    if (name_len > 0) {
        memcpy(p + 39, mission->name, name_len);
    }
    return 39 + name_len;
}

gp_frame_error gp_plan_piece_unpack(const gp_frame *frame, uint16_t *offset, uint16_t *total,
                                    const uint8_t **data, uint16_t *len)
{
    if (frame->type != GP_MSG_PLAN || frame->length < 4 || frame->length > 4 + GP_PLAN_PIECE) {
        return GP_FRAME_LENGTH;
    }
    *offset = get_u16(frame->payload);
    *total = get_u16(frame->payload + 2);
    *data = frame->payload + 4;
    *len = (uint16_t)(frame->length - 4);
    return GP_FRAME_OK;
}

size_t gp_plan_status_pack(int accepted, const char *message, uint8_t *p)
{
    size_t len = strlen(message);
    if (len > GP_MAX_PAYLOAD - 2) {
        len = GP_MAX_PAYLOAD - 2;
    }
    p[0] = accepted ? 1 : 0;
    p[1] = (uint8_t)len;
    memcpy(p + 2, message, len);
    return 2 + len;
}
