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

void test_cobs_should_encode_the_reference_examples(void)
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
        uint8_t out[16], back[16];
        CHECK_INT(gp_cobs_encode(rows[i].raw, rows[i].raw_len, out), rows[i].encoded_len);
        CHECK(memcmp(out, rows[i].encoded, rows[i].encoded_len) == 0);
        CHECK_INT(gp_cobs_decode(out, rows[i].encoded_len, back, sizeof back), rows[i].raw_len);
        CHECK(memcmp(back, rows[i].raw, rows[i].raw_len) == 0);
    }
    uint8_t long_run[254], out[300], back[300];
    for (int i = 0; i < 254; i++) {
        long_run[i] = (uint8_t)(i + 1);
    }
    size_t n = gp_cobs_encode(long_run, 254, out);
    CHECK_INT(n, 256);  /* 0xFF block, then an empty block */
    CHECK_INT(out[0], 0xFF);
    CHECK_INT(gp_cobs_decode(out, n, back, sizeof back), 254);
}

void test_command_should_round_trip_through_a_frame(void)
{
    gp_command command = {.tick = 123456, .state = 2, .stack_depth = 1, .transition = 3,
                          .from = 0, .to = 1, .profile = 1, .flags = GP_FLAG_CLIMBING,
                          .depth_target_m = 5.5f, .pitch_rad = 0.454f, .ballast_cc = 230,
                          .heading_rad = 1.25f, .sensor_power = 0x207, .event_count = 9};
    uint8_t payload[GP_COMMAND_SIZE], wire[GP_MAX_FRAME];
    CHECK_INT(gp_command_pack(&command, payload), 36);
    size_t n = gp_frame_build(GP_MSG_COMMAND, 7, 6, payload, sizeof payload, wire);
    CHECK_INT(wire[n - 1], 0);
    for (size_t i = 0; i + 1 < n; i++) {
        CHECK(wire[i] != 0);
    }
    gp_frame frame;
    CHECK_INT(gp_frame_parse(wire, n - 1, &frame), GP_FRAME_OK);
    CHECK_INT(frame.seq, 7);
    CHECK_INT(frame.ack, 6);
    gp_command back;
    CHECK_INT(gp_command_unpack(&frame, &back), GP_FRAME_OK);
    CHECK_INT(back.tick, 123456);
    CHECK_INT(back.to, 1);
    CHECK_NEAR(back.pitch_rad, 0.454, 1e-6);  /* f32 on the wire */
    CHECK_INT(back.sensor_power, 0x207);
    CHECK_INT(back.event_count, 9);
}

void test_sensors_should_update_only_the_masked_values(void)
{
    double in[GP_N_SENSORS] = {0}, out[GP_N_SENSORS];
    in[0] = 500;
    in[9] = 14.25;
    in[1] = 99;  /* not in the mask: must not arrive */
    for (int i = 0; i < GP_N_SENSORS; i++) {
        out[i] = -1;
    }
    gp_frame frame = {.type = GP_MSG_SENSORS};
    frame.length = (uint16_t)gp_sensors_pack(42, (1u << 0) | (1u << 9), in, frame.payload);
    CHECK_INT(frame.length, 16);
    uint32_t tick;
    CHECK_INT(gp_sensors_unpack(&frame, &tick, out), GP_FRAME_OK);
    CHECK_INT(tick, 42);
    CHECK_NEAR(out[0], 500, 0);
    CHECK_NEAR(out[9], 14.25, 0);
    CHECK_NEAR(out[1], -1, 0);
    frame.length--;  /* a payload that disagrees with its mask */
    CHECK_INT(gp_sensors_unpack(&frame, &tick, out), GP_FRAME_LENGTH);
}

static size_t raw_packet(uint8_t version, uint8_t type, uint16_t length_field,
                         const uint8_t *payload, size_t payload_len, uint8_t *wire)
{
    uint8_t packet[GP_MAX_PACKET + 16] = {version, type, 1, 0, (uint8_t)length_field,
                                          (uint8_t)(length_field >> 8)};
    memcpy(packet + 6, payload, payload_len);
    uint16_t crc = gp_crc16(packet, 6 + payload_len);
    packet[6 + payload_len] = (uint8_t)(crc >> 8);
    packet[7 + payload_len] = (uint8_t)crc;
    return gp_cobs_encode(packet, 8 + payload_len, wire);
}

void test_bad_frames_should_be_dropped_with_their_reason(void)
{
    uint8_t wire[600], payload[4] = {1, 2, 3, 4};
    gp_frame frame;
    size_t n = raw_packet(2, GP_MSG_NAK, 0, payload, 0, wire);
    CHECK_INT(gp_frame_parse(wire, n, &frame), GP_FRAME_VERSION);
    n = raw_packet(1, 0x42, 0, payload, 0, wire);
    CHECK_INT(gp_frame_parse(wire, n, &frame), GP_FRAME_TYPE);
    n = raw_packet(1, GP_MSG_RELEASE, 3, payload, 4, wire);
    CHECK_INT(gp_frame_parse(wire, n, &frame), GP_FRAME_LENGTH);
    n = gp_frame_build(GP_MSG_RELEASE, 1, 0, payload, 1, wire) - 1;
    wire[3] ^= 0x20;
    CHECK_INT(gp_frame_parse(wire, n, &frame), GP_FRAME_CRC);
    CHECK_INT(gp_frame_parse((const uint8_t *)"\x05\x11\x22", 3, &frame), GP_FRAME_COBS);
    CHECK_INT(gp_frame_parse((const uint8_t *)"\x03\x01\x02", 3, &frame), GP_FRAME_SHORT);
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
    uint8_t wire[GP_MAX_FRAME], payload[GP_MAX_PAYLOAD];
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
        CHECK_INT(gp_frame_parse(wire, n - 1, &frame), GP_FRAME_OK);
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
