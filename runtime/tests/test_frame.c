/* Framing of docs/protocol.md: reference vectors, round trips, every kind of bad
 * frame, and random bytes that must never crash the reader. */
#include <string.h>

#include "gp_crc.h"
#include "gp_frame.h"
#include "gp_test.h"

/* The reader fed one byte at a time: the hardest way to split a stream. */
static int push(gp_frame_reader *reader, uint8_t byte, gp_frame *out)
{
    size_t used;
    int result = gp_frame_reader_feed(reader, &byte, 1, &used, out);
    CHECK_INT(used, 1);
    return result;
}

void test_crc_should_match_catalogue_check_values(void)
{
    const uint8_t *check = (const uint8_t *)"123456789";
    CHECK_INT(gp_crc16(check, 9), 0x29B1);         /* CRC-16/CCITT-FALSE */
    CHECK_INT(gp_crc32(0, check, 9), 0xCBF43926u);  /* CRC-32/ISO-HDLC */
    CHECK_INT(gp_crc32(gp_crc32(0, check, 4), check + 4, 5), 0xCBF43926u);
}

/* The definition, one bit at a time: the reference for the table-driven CRC-16. */
static uint16_t crc16_bitwise(const uint8_t *data, size_t len)
{
    uint16_t crc = 0xFFFFu;
    for (size_t i = 0; i < len; i++) {
        crc ^= (uint16_t)(data[i] << 8);
        for (int bit = 0; bit < 8; bit++) {
            crc = (crc & 0x8000u) ? (uint16_t)((crc << 1) ^ 0x1021u) : (uint16_t)(crc << 1);
        }
    }
    return crc;
}

/* CRC-32/ISO-HDLC one bit at a time, continued from `crc`: the reference for the sliced one. */
static uint32_t crc32_bitwise(uint32_t crc, const uint8_t *data, size_t len)
{
    crc = ~crc;
    for (size_t i = 0; i < len; i++) {
        crc ^= data[i];
        for (int bit = 0; bit < 8; bit++) {
            crc = (crc & 1u) ? (crc >> 1) ^ 0xEDB88320u : crc >> 1;
        }
    }
    return ~crc;
}

/* Every length (a multiple of the slice or not) at every alignment, and a CRC-32 taken
 * in two pieces split anywhere. */
void test_crcs_should_equal_their_bitwise_definitions(void)
{
    uint8_t data[304];
    unsigned seed = 99;
    for (int round = 0; round < 500; round++) {
        size_t offset = gp_test_random(&seed) % 4;
        size_t len = gp_test_random(&seed) % (sizeof data - offset);
        for (size_t i = 0; i < offset + len; i++) {
            data[i] = (uint8_t)gp_test_random(&seed);
        }
        const uint8_t *p = data + offset;
        CHECK_INT(gp_crc16(p, len), crc16_bitwise(p, len));
        uint32_t whole = crc32_bitwise(0, p, len);
        CHECK_INT(gp_crc32(0, p, len), whole);
        size_t split = len ? gp_test_random(&seed) % len : 0;
        CHECK_INT(gp_crc32(gp_crc32(0, p, split), p + split, len - split), whole);
    }
}

void test_cobs_should_encode_the_reference_examples_in_place(void)
{
    static const struct {
        uint8_t raw[8];
        size_t raw_len;
        uint8_t encoded[8];
        size_t encoded_len;
    } rows[] = {
        {{0x00}, 1, {0x01, 0x01}, 2},
        {{0x00, 0x00}, 2, {0x01, 0x01, 0x01}, 3},
        {{0x11, 0x22, 0x00, 0x33}, 4, {0x03, 0x11, 0x22, 0x02, 0x33}, 5},
        {{0x11, 0x22, 0x33, 0x44}, 4, {0x05, 0x11, 0x22, 0x33, 0x44}, 5},
        {{0x11, 0x00, 0x00, 0x00}, 4, {0x02, 0x11, 0x01, 0x01, 0x01}, 5},
    };
    for (unsigned i = 0; i < sizeof rows / sizeof rows[0]; i++) {
        uint8_t buf[16];
        memset(buf, 0x5A, sizeof buf);
        memcpy(buf + 1, rows[i].raw, rows[i].raw_len);  /* buf[0]: room for a code byte */
        CHECK_INT(gp_cobs_encode(buf, rows[i].raw_len), rows[i].encoded_len);
        CHECK(memcmp(buf, rows[i].encoded, rows[i].encoded_len) == 0);
        CHECK_INT(buf[rows[i].encoded_len], 0);
        CHECK_INT(gp_cobs_decode(buf, rows[i].encoded_len), rows[i].raw_len);
        CHECK(memcmp(buf + 1, rows[i].raw, rows[i].raw_len) == 0);
    }
    /* the longest packet without a zero is one block; a block of 254 bytes (code 0xFF)
     * would decode to more than a packet can hold */
    uint8_t run[GP_MAX_PACKET + 2];
    for (int i = 1; i <= GP_MAX_PACKET + 1; i++) {
        run[i] = (uint8_t)i;
    }
    CHECK_INT(gp_cobs_encode(run, GP_MAX_PACKET), GP_MAX_PACKET + 1);
    CHECK_INT(run[0], GP_MAX_PACKET + 1);
    CHECK_INT(run[GP_MAX_PACKET + 1], 0);  /* the delimiter */
    CHECK_INT(gp_cobs_decode(run, GP_MAX_PACKET + 1), GP_MAX_PACKET);
    CHECK_INT(run[GP_MAX_PACKET], GP_MAX_PACKET);
    uint8_t full_block[] = {0xFF, 1, 2, 3};
    CHECK_INT(gp_cobs_decode(full_block, sizeof full_block), -1);
}

static gp_frame_error reframe(uint8_t type, const uint8_t *payload, size_t len, uint8_t *wire,
                              gp_frame *frame)
{
    size_t n = gp_frame_build(type, 7, 6, payload, len, wire);
    CHECK_INT(wire[n - 1], 0);
    for (size_t i = 0; i + 1 < n; i++) {
        CHECK(wire[i] != 0);
    }
    return gp_frame_parse(wire, n - 1, frame);
}

void test_command_should_travel_whole_and_as_its_changes(void)
{
    gp_command base = {.tick = 123455, .state = 2, .stack_depth = 1, .from = GP_NO_STATE,
                       .to = GP_NO_STATE, .profile = 1, .flags = GP_FLAG_CLIMBING,
                       .depth_target_m = 5.5f, .pitch_rad = 0.454f, .ballast_cc = 230,
                       .heading_rad = 1.25f, .sensor_power = 0x207, .event_count = 9};
    gp_command command = base, back;
    command.tick = 123456;
    uint8_t payload[GP_COMMAND_MAX_SIZE], wire[GP_MAX_FRAME];
    gp_frame frame;

    /* whole: every field that is not zero; it needs no base */
    size_t len = gp_command_pack(&command, NULL, payload);
    CHECK_INT(len, 7 + 6 + 4 * 4 + 4 + 4);  /* transition is 0: left out */
    CHECK_INT(payload[4], 0);
    CHECK_INT(reframe(GP_MSG_COMMAND, payload, len, wire, &frame), GP_FRAME_OK);
    CHECK_INT(frame.seq, 7);
    CHECK_INT(frame.ack, 6);
    CHECK_INT(gp_command_unpack(&frame, NULL, &back), GP_FRAME_OK);
    CHECK(memcmp(&back, &command, sizeof back) == 0);

    /* unchanged from the tick before: the tick, its base one tick back, no field */
    CHECK_INT(gp_command_pack(&command, &base, payload), 7);
    CHECK_INT(payload[4], 1);
    /* a turn: three fields change, and a negative zero is not a zero */
    command.flags = 0;
    command.depth_target_m = 20.0f;
    command.pitch_rad = -0.454f;
    command.ballast_cc = -0.0f;
    len = gp_command_pack(&command, &base, payload);
    CHECK_INT(len, 7 + 1 + 4 + 4 + 4);
    CHECK_INT(reframe(GP_MSG_COMMAND, payload, len, wire, &frame), GP_FRAME_OK);
    CHECK_INT(gp_command_unpack(&frame, &base, &back), GP_FRAME_OK);
    CHECK(memcmp(&back, &command, sizeof back) == 0);
    CHECK(signbit(back.ballast_cc));
    /* the receiver holds another COMMAND than the base: it cannot apply it */
    gp_command other = base;
    other.tick = 123454;
    CHECK_INT(gp_command_unpack(&frame, &other, &back), GP_FRAME_BASE);
    CHECK_INT(gp_command_unpack(&frame, NULL, &back), GP_FRAME_BASE);
    /* a base more than 255 ticks back cannot be named: whole (5 bytes, 4 floats, 2 words) */
    base.tick = 123456 - 256;
    len = gp_command_pack(&command, &base, payload);
    CHECK_INT(len, 7 + 5 + 4 * 4 + 4 + 4);
    CHECK_INT(payload[4], 0);
    /* a fields mask with an unknown bit, a length that disagrees with the mask */
    frame.payload = payload;
    frame.length = (uint16_t)len;
    CHECK_INT(gp_command_unpack(&frame, NULL, &back), GP_FRAME_OK);
    payload[6] |= 0x80;
    CHECK_INT(gp_command_unpack(&frame, NULL, &back), GP_FRAME_LENGTH);
    payload[6] &= 0x7F;
    frame.length--;
    CHECK_INT(gp_command_unpack(&frame, NULL, &back), GP_FRAME_LENGTH);
}

/* Each field alone, as the contract sizes it (GP_COMMAND_FIELD_BYTES), reads and packs
 * back to the same bytes. */
void test_command_fields_should_have_their_contract_sizes(void)
{
    static const uint8_t bytes[GP_N_COMMAND_FIELDS] = GP_COMMAND_FIELD_BYTES;
    for (int field = 0; field < GP_N_COMMAND_FIELDS; field++) {
        uint8_t payload[GP_COMMAND_MAX_SIZE] = {9, 0, 0, 0, 0, (uint8_t)(1u << field),
                                                (uint8_t)((1u << field) >> 8)};
        memset(payload + 7, 0x41, bytes[field]);
        gp_frame frame = {GP_MSG_COMMAND, 1, 0, (uint16_t)(7 + bytes[field]), payload};
        gp_command command;
        uint8_t again[GP_COMMAND_MAX_SIZE];
        CHECK_INT(gp_command_unpack(&frame, NULL, &command), GP_FRAME_OK);
        CHECK_INT(gp_command_pack(&command, NULL, again), 7 + bytes[field]);
        CHECK(memcmp(again, payload, 7u + bytes[field]) == 0);
    }
}

void test_sensors_should_update_only_the_masked_values(void)
{
    double in[GP_N_SENSORS] = {0}, out[GP_N_SENSORS];
    const uint32_t read_mask = (1u << 0) | (1u << 9);
    uint8_t payload[GP_MAX_PAYLOAD];
    in[0] = 500;
    in[9] = 14.25;
    in[1] = 99;  /* not in the mask: must not arrive */
    for (int i = 0; i < GP_N_SENSORS; i++) {
        out[i] = -1;
    }
    /* the runtime's read mask: no mask on the wire */
    gp_frame frame = {.type = GP_MSG_SENSORS, .payload = payload};
    frame.length = (uint16_t)gp_sensors_pack(42, 0, read_mask, read_mask, in, payload);
    CHECK_INT(frame.length, 5 + 8);
    uint32_t tick;
    uint8_t flags;
    CHECK_INT(gp_sensors_unpack(&frame, read_mask, &tick, &flags, out), GP_FRAME_OK);
    CHECK_INT(tick, 42);
    CHECK_INT(flags, 0);
    CHECK_NEAR(out[0], 500, 0);
    CHECK_NEAR(out[9], 14.25, 0);
    CHECK_NEAR(out[1], -1, 0);
    frame.length--;  /* a payload that disagrees with its mask */
    CHECK_INT(gp_sensors_unpack(&frame, read_mask, &tick, &flags, out), GP_FRAME_LENGTH);
    /* another set (the CTD is off): the mask goes with it; a resync request */
    out[9] = -1;
    frame.length = (uint16_t)gp_sensors_pack(43, GP_SENSORS_RESYNC, 1u, read_mask, in, payload);
    CHECK_INT(frame.length, 5 + 4 + 4);
    CHECK_INT(gp_sensors_unpack(&frame, read_mask, &tick, &flags, out), GP_FRAME_OK);
    CHECK_INT(flags, GP_SENSORS_MASK | GP_SENSORS_RESYNC);
    CHECK_NEAR(out[9], -1, 0);
    payload[4] |= 0x80;  /* a reserved flag: dropped */
    CHECK_INT(gp_sensors_unpack(&frame, read_mask, &tick, &flags, out), GP_FRAME_LENGTH);
}

static size_t raw_packet(uint8_t version, uint8_t type, uint16_t length_field,
                         const uint8_t *payload, size_t payload_len, uint8_t *wire)
{
    uint8_t *packet = wire + 1;
    packet[0] = version;
    packet[1] = type;
    packet[2] = 1;
    packet[3] = 0;
    packet[4] = (uint8_t)length_field;
    packet[5] = (uint8_t)(length_field >> 8);
    memcpy(packet + 6, payload, payload_len);
    uint16_t crc = gp_crc16(packet, 6 + payload_len);
    packet[6 + payload_len] = (uint8_t)(crc >> 8);
    packet[7 + payload_len] = (uint8_t)crc;
    return gp_cobs_encode(wire, 8 + payload_len);
}

void test_bad_frames_should_be_dropped_with_their_reason(void)
{
    uint8_t wire[600], payload[4] = {1, 2, 3, 4};
    gp_frame frame;
    size_t n = raw_packet(GP_PROTOCOL_VERSION + 1, GP_MSG_NAK, 0, payload, 0, wire);
    CHECK_INT(gp_frame_parse(wire, n, &frame), GP_FRAME_VERSION);
    n = raw_packet(GP_PROTOCOL_VERSION, 0x42, 0, payload, 0, wire);
    CHECK_INT(gp_frame_parse(wire, n, &frame), GP_FRAME_TYPE);
    n = raw_packet(GP_PROTOCOL_VERSION, GP_MSG_RELEASE, 3, payload, 4, wire);
    CHECK_INT(gp_frame_parse(wire, n, &frame), GP_FRAME_LENGTH);
    n = gp_frame_build(GP_MSG_RELEASE, 1, 0, payload, 1, wire) - 1;
    wire[3] ^= 0x20;
    CHECK_INT(gp_frame_parse(wire, n, &frame), GP_FRAME_CRC);
    uint8_t past_end[] = {0x05, 0x11, 0x22}, zero_inside[] = {0x03, 0x11, 0x00};
    uint8_t short_packet[] = {0x03, 0x01, 0x02};
    CHECK_INT(gp_frame_parse(past_end, 3, &frame), GP_FRAME_COBS);
    CHECK_INT(gp_frame_parse(zero_inside, 3, &frame), GP_FRAME_COBS);
    CHECK_INT(gp_frame_parse(short_packet, 3, &frame), GP_FRAME_SHORT);
    memset(wire, 1, 300);
    CHECK_INT(gp_frame_parse(wire, 251, &frame), GP_FRAME_TOO_LONG);
    uint8_t big[GP_MAX_PAYLOAD + 1] = {0};
    CHECK_INT(gp_frame_build(GP_MSG_PLAN, 1, 0, big, sizeof big, wire), 0);
}

void test_reader_should_resynchronise_after_garbage(void)
{
    gp_frame_reader reader = {0};
    gp_frame frame;
    uint8_t wire[GP_MAX_FRAME];
    int results[4], n_results = 0;
    for (int i = 0; i < 400; i++) {  /* an overlong run of non-zero bytes */
        CHECK_INT(push(&reader, 0x07, &frame), -1);
    }
    results[n_results++] = push(&reader, 0, &frame);
    CHECK_INT(push(&reader, 0, &frame), -1);  /* empty frame: ignored */
    size_t n = gp_frame_build(GP_MSG_NAK, 9, 0, NULL, 0, wire);
    for (size_t i = 0; i < n; i++) {
        int r = push(&reader, wire[i], &frame);
        if (r >= 0) {
            results[n_results++] = r;
        }
    }
    CHECK_INT(n_results, 2);
    CHECK_INT(results[0], GP_FRAME_TOO_LONG);
    CHECK_INT(results[1], GP_FRAME_OK);
    CHECK_INT(frame.type, GP_MSG_NAK);
    CHECK_INT(frame.seq, 9);
}

void test_random_bytes_should_never_crash_the_reader(void)
{
    gp_frame_reader reader = {0};
    gp_frame frame;
    unsigned seed = 77, frames = 0;
    uint8_t wire[GP_MAX_FRAME], copy[GP_MAX_FRAME], payload[GP_MAX_PAYLOAD];
    for (int i = 0; i < 200000; i++) {
        uint8_t byte = (uint8_t)gp_test_random(&seed);
        if (byte < 8) {
            byte = 0;  /* frequent delimiters: many short frames */
        }
        int r = push(&reader, byte, &frame);
        if (r >= 0) {
            frames++;
            CHECK(r <= GP_FRAME_TYPE);
        }
    }
    CHECK(frames > 1000);
    /* valid frames with random payloads, corrupted in one byte: never accepted intact */
    for (int i = 0; i < 5000; i++) {
        size_t len = gp_test_random(&seed) % (GP_MAX_PAYLOAD + 1);
        for (size_t j = 0; j < len; j++) {
            payload[j] = (uint8_t)gp_test_random(&seed);
        }
        size_t n = gp_frame_build(GP_MSG_PLAN, (uint8_t)i, 0, payload, len, wire);
        memcpy(copy, wire, n);  /* parsing decodes in place */
        CHECK_INT(gp_frame_parse(copy, n - 1, &frame), GP_FRAME_OK);
        CHECK(frame.length == len && memcmp(frame.payload, payload, len) == 0);
        size_t at = gp_test_random(&seed) % (n - 1);
        uint8_t flip = (uint8_t)(1u << (gp_test_random(&seed) % 8));
        wire[at] ^= flip;
        if (wire[at] != 0) {
            CHECK(gp_frame_parse(wire, n - 1, &frame) != GP_FRAME_OK);
        }
    }
}

void test_hello_should_carry_the_raw_mission_hash(void)
{
    uint8_t payload[GP_MAX_PAYLOAD];
    size_t n = gp_hello_pack(&gp_mission_table, payload);
    CHECK_INT(n, 39 + strlen("sampleMission"));
    CHECK_INT(payload[1], GP_N_SENSORS);
    CHECK_INT(payload[6], 0x5d);
    CHECK_INT(payload[37], 0xb9);
    CHECK_INT(payload[38], 13);
    CHECK(memcmp(payload + 39, "sampleMission", 13) == 0);
}

void test_reader_should_split_one_chunk_into_its_frames(void)
{
    uint8_t stream[3 * GP_MAX_FRAME + 16];
    size_t n = 0;
    n += gp_frame_build(GP_MSG_NAK, 1, 0, NULL, 0, stream + n);
    memcpy(stream + n, "\x13\x37\x00", 3);  /* a damaged frame between two good ones */
    n += 3;
    n += gp_frame_build(GP_MSG_NAK, 2, 0, NULL, 0, stream + n);
    size_t third = gp_frame_build(GP_MSG_NAK, 3, 0, NULL, 0, stream + n);
    n += third - 4;  /* the third is cut short */
    gp_frame_reader reader = {0};
    gp_frame frame;
    int results[8], seqs[8], count = 0;
    for (size_t i = 0, used; i < n && count < 8; i += used) {
        int r = gp_frame_reader_feed(&reader, stream + i, n - i, &used, &frame);
        if (r >= 0) {
            seqs[count] = r == GP_FRAME_OK ? frame.seq : -1;
            results[count++] = r;
        }
    }
    CHECK_INT(count, 3);
    CHECK_INT(results[0], GP_FRAME_OK);
    CHECK_INT(seqs[0], 1);
    CHECK(results[1] != GP_FRAME_OK);
    CHECK_INT(results[2], GP_FRAME_OK);
    CHECK_INT(seqs[2], 2);
    CHECK_INT(reader.len, third - 4);  /* the cut frame waits for the rest */
}
