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

/* COBS in place. A packet of at most GP_MAX_PACKET bytes has no run of 254 non-zero
 * bytes, so every block ends in a zero (or the packet's end) and a code byte is the
 * distance to it: encoding turns each zero into a code byte, decoding turns each code
 * byte back into a zero. Nothing is copied; decoding touches one byte per block. */
size_t gp_cobs_encode(uint8_t *buf, size_t len)
{
    uint8_t *code_at = buf, *end = buf + 1 + len;
    *end = 0;  /* the delimiter's place: it ends the last block */
    for (uint8_t *p = buf + 1;; p++) {
        while (*p != 0) {
            p++;
        }
        *code_at = (uint8_t)(p - code_at);
        if (p == end) {
            return len + 1;
        }
        code_at = p;
    }
}

int gp_cobs_decode(uint8_t *buf, size_t len)
{
    size_t at = 0;
    while (at < len) {
        size_t code = buf[at];
        if (code == 0 || code == 0xFF) {
            return -1;
        }
        buf[at] = 0;  /* the zero that ended the block before (before the packet: unused) */
        at += code;
    }
    return at == len ? (int)len - 1 : -1;
}

size_t gp_frame_seal(uint8_t *wire, uint8_t type, uint8_t seq, uint8_t ack, size_t len)
{
    if (len > GP_MAX_PAYLOAD) {
        return 0;
    }
    uint8_t *packet = wire + 1;
    packet[0] = GP_PROTOCOL_VERSION;
    packet[1] = type;
    packet[2] = seq;
    packet[3] = ack;
    put_u16(packet + 4, (uint16_t)len);
    uint16_t crc = gp_crc16(packet, 6 + len);
    packet[6 + len] = (uint8_t)(crc >> 8);
    packet[7 + len] = (uint8_t)crc;
    return gp_cobs_encode(wire, 8 + len) + 1;  /* with the delimiter it wrote */
}

size_t gp_frame_build(uint8_t type, uint8_t seq, uint8_t ack, const uint8_t *payload,
                      size_t len, uint8_t *wire)
{
    if (len > GP_MAX_PAYLOAD) {
        return 0;
    }
    if (len > 0) {
        memcpy(wire + GP_FRAME_PAYLOAD_AT, payload, len);
    }
    return gp_frame_seal(wire, type, seq, ack, len);
}

static int known_type(uint8_t type)
{
    return type == GP_MSG_HELLO || type == GP_MSG_SENSORS || type == GP_MSG_COMMAND
        || type == GP_MSG_RELEASE || type == GP_MSG_PLAN || type == GP_MSG_PLAN_STATUS
        || type == GP_MSG_PLAN_UPDATE || type == GP_MSG_UPDATE_STATUS || type == GP_MSG_NAK;
}

/* A frame's bytes, which hold no zero (the reader split them at the delimiters). */
static gp_frame_error decode(uint8_t *wire, size_t len, gp_frame *out)
{
    if (len > GP_MAX_WIRE) {
        return GP_FRAME_TOO_LONG;
    }
    int n = gp_cobs_decode(wire, len);
    if (n < 0) {
        return GP_FRAME_COBS;
    }
    if (n < 8) {
        return GP_FRAME_SHORT;
    }
    const uint8_t *packet = wire + 1;
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
    out->payload = packet + 6;
    return GP_FRAME_OK;
}

gp_frame_error gp_frame_parse(uint8_t *wire, size_t len, gp_frame *out)
{
    if (len > GP_MAX_WIRE) {
        return GP_FRAME_TOO_LONG;
    }
    return memchr(wire, 0, len) ? GP_FRAME_COBS : decode(wire, len, out);
}

int gp_frame_reader_feed(gp_frame_reader *reader, uint8_t *data, size_t len, size_t *used,
                         gp_frame *out)
{
    uint8_t *zero = memchr(data, 0, len);
    size_t run = zero ? (size_t)(zero - data) : len;
    if (zero && reader->len == 0 && !reader->overlong) {  /* whole in `data`: no copy */
        *used = run + 1;
        return run == 0 ? -1 : (int)decode(data, run, out);
    }
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
        result = (int)decode(reader->buf, reader->len, out);
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
    case GP_FRAME_BASE: return "no such base";
    }
    return "?";
}

/* ---- payloads ---------------------------------------------------------------- */

gp_frame_error gp_sensors_unpack(const gp_frame *frame, uint32_t read_mask, uint32_t *tick,
                                 uint8_t *flags, double *sensors)
{
    const uint8_t *p = frame->payload, *end = frame->payload + frame->length;
    if (frame->type != GP_MSG_SENSORS || frame->length < 5
        || (p[4] & ~(GP_SENSORS_MASK | GP_SENSORS_RESYNC)) != 0) {
        return GP_FRAME_LENGTH;
    }
    uint32_t mask = read_mask;
    *tick = get_u32(p);
    *flags = p[4];
    p += 5;
    if (*flags & GP_SENSORS_MASK) {
        if (end - p < 4) {
            return GP_FRAME_LENGTH;
        }
        mask = get_u32(p);
        p += 4;
    }
    unsigned count = 0;
    for (uint32_t m = mask; m != 0; m &= m - 1) {  /* one round per set bit */
        count++;
    }
    if ((size_t)(end - p) != 4u * count) {
        return GP_FRAME_LENGTH;
    }
    for (uint32_t m = mask; m != 0; m &= m - 1, p += 4) {
        int i = __builtin_ctz(m);  /* the lowest set bit: the next value's sensor */
        if (i < GP_N_SENSORS) {
            sensors[i] = (double)get_f32(p);
        }
    }
    return GP_FRAME_OK;
}

size_t gp_sensors_pack(uint32_t tick, uint8_t flags, uint32_t mask, uint32_t read_mask,
                       const double *sensors, uint8_t *payload)
{
    put_u32(payload, tick);
    size_t n = 5;
    if (mask != read_mask) {
        flags |= GP_SENSORS_MASK;
        put_u32(payload + n, mask);
        n += 4;
    }
    payload[4] = flags;
    for (int i = 0; i < GP_N_SENSORS; i++) {
        if ((mask >> i) & 1u) {
            put_f32(payload + n, (float)sensors[i]);
            n += 4;
        }
    }
    return n;
}

/* ---- COMMAND: fields against a base ------------------------------------------------ */

/* Each field in gp_command_field order: its bit, the gp_command member, its wire kind.
 * Unrolled, a tick in which three fields changed costs a compare per field. */
#define COMMAND_FIELDS(X)                                                               \
    X(GP_CMD_STATE, state, u8) X(GP_CMD_STACK_DEPTH, stack_depth, u8)                   \
    X(GP_CMD_TRANSITION, transition, u8) X(GP_CMD_FROM_STATE, from, u8)                 \
    X(GP_CMD_TO_STATE, to, u8) X(GP_CMD_PROFILE, profile, u8) X(GP_CMD_FLAGS, flags, u8) \
    X(GP_CMD_DEPTH_TARGET_M, depth_target_m, f32) X(GP_CMD_PITCH_RAD, pitch_rad, f32)   \
    X(GP_CMD_BALLAST_CC, ballast_cc, f32) X(GP_CMD_HEADING_RAD, heading_rad, f32)       \
    X(GP_CMD_SENSOR_POWER, sensor_power, u32) X(GP_CMD_EVENT_COUNT, event_count, u32)   \
    X(GP_CMD_SPEED_MPS, speed_mps, f32) X(GP_CMD_THRUST_W, thrust_w, f32)

/* A field's value as it travels: an f32 by its bits (-0 and NaNs are kept). */
static uint32_t bits_u8(uint8_t v) { return v; }
static uint32_t bits_u32(uint32_t v) { return v; }
static uint32_t bits_f32(float v)
{
    uint32_t bits;
    memcpy(&bits, &v, sizeof bits);
    return bits;
}

static uint8_t *write_u8(uint8_t *p, uint32_t bits) { *p = (uint8_t)bits; return p + 1; }
static uint8_t *write_u32(uint8_t *p, uint32_t bits) { put_u32(p, bits); return p + 4; }
#define write_f32 write_u32

static const uint8_t *read_u8(const uint8_t *p, uint8_t *v) { *v = *p; return p + 1; }
static const uint8_t *read_u32(const uint8_t *p, uint32_t *v) { *v = get_u32(p); return p + 4; }
static const uint8_t *read_f32(const uint8_t *p, float *v) { *v = get_f32(p); return p + 4; }

static const gp_command zero_command;

size_t gp_command_pack(const gp_command *c, const gp_command *base, uint8_t *p)
{
    uint32_t back = base ? c->tick - base->tick : 0;
    if (back == 0 || back > 0xFFu) {
        base = &zero_command;
        back = 0;
    }
    put_u32(p, c->tick);
    p[4] = (uint8_t)back;
    uint32_t fields = 0;
    uint8_t *at = p + 7;
#define PACK(bit, member, kind)                                    \
    if (bits_##kind(c->member) != bits_##kind(base->member)) {     \
        fields |= 1u << (bit);                                     \
        at = write_##kind(at, bits_##kind(c->member));             \
    }
    COMMAND_FIELDS(PACK)
#undef PACK
    put_u16(p + 5, (uint16_t)fields);
    return (size_t)(at - p);
}

gp_frame_error gp_command_unpack(const gp_frame *frame, const gp_command *base,
                                 gp_command *c)
{
    static const uint8_t field_bytes[GP_N_COMMAND_FIELDS] = GP_COMMAND_FIELD_BYTES;
    const uint8_t *p = frame->payload;
    if (frame->type != GP_MSG_COMMAND || frame->length < 7) {
        return GP_FRAME_LENGTH;
    }
    uint32_t tick = get_u32(p);
    uint8_t back = p[4];
    uint32_t fields = get_u16(p + 5);
    if (fields >> GP_N_COMMAND_FIELDS) {
        return GP_FRAME_LENGTH;
    }
    size_t size = 7;
    for (int i = 0; i < GP_N_COMMAND_FIELDS; i++) {
        size += ((fields >> i) & 1u) ? field_bytes[i] : 0;
    }
    if (size != frame->length) {
        return GP_FRAME_LENGTH;
    }
    if (back == 0) {
        base = &zero_command;
    } else if (!base || base->tick != tick - back) {
        return GP_FRAME_BASE;
    }
    gp_command out = *base;
    out.tick = tick;
    p += 7;
#define UNPACK(bit, member, kind)                  \
    if (fields & (1u << (bit))) {                  \
        p = read_##kind(p, &out.member);           \
    }
    COMMAND_FIELDS(UNPACK)
#undef UNPACK
    *c = out;
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
    for (int i = 0; i < GP_MISSION_HASH_BYTES; i++) {
        int hi = hash ? hex_digit(hash[2 * i]) : -1;
        int lo = hi >= 0 ? hex_digit(hash[2 * i + 1]) : -1;
        p[6 + i] = (hi < 0 || lo < 0) ? 0 : (uint8_t)(hi * 16 + lo);
    }
    size_t name_len = mission->name ? strlen(mission->name) : 0;
    if (name_len > GP_MAX_PAYLOAD - GP_HELLO_FIXED_BYTES) {
        name_len = GP_MAX_PAYLOAD - GP_HELLO_FIXED_BYTES;
    }
    p[GP_HELLO_FIXED_BYTES - 1] = (uint8_t)name_len;
    if (name_len > 0) {
        memcpy(p + GP_HELLO_FIXED_BYTES, mission->name, name_len);
    }
    return GP_HELLO_FIXED_BYTES + name_len;
}

gp_frame_error gp_plan_piece_unpack(const gp_frame *frame, uint16_t *offset, uint16_t *total,
                                    const uint8_t **data, uint16_t *len)
{
    if ((frame->type != GP_MSG_PLAN && frame->type != GP_MSG_PLAN_UPDATE) || frame->length < 4
        || frame->length > 4 + GP_PLAN_PIECE) {
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

size_t gp_update_status_pack(uint8_t status, uint32_t seq, const char *message, uint8_t *p)
{
    size_t len = strlen(message);
    if (len > GP_MAX_PAYLOAD - 6) {
        len = GP_MAX_PAYLOAD - 6;
    }
    p[0] = status;
    put_u32(p + 1, seq);
    p[5] = (uint8_t)len;
    memcpy(p + 6, message, len);
    return 6 + len;
}
