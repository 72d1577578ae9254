/* libFuzzer harness for the frame decoder (docs/protocol.md).
 *
 * Input byte 0, low bit clear: the rest is a packet (version, type, seq, ack, length,
 * payload) to which the harness appends its CRC-16, then COBS-encodes it, so the fuzzer
 * explores what lies behind the checksum: version, length and type checks and the
 * payload unpackers. A packet the decoder accepts must build back to the same wire
 * bytes, and a COMMAND read whole must pack whole again to the same COMMAND. Low bit
 * set: the rest goes to the frame reader raw (delimiters, overlong runs, bad COBS, bad
 * CRCs), as a corrupted serial line delivers it.
 */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "gp_crc.h"
#include "gp_frame.h"
#include "gp_mission.h"

static void unpack_payloads(const gp_frame *frame)
{
    uint32_t tick;
    uint8_t flags;
    double sensors[GP_N_SENSORS];
    gp_command command, again;
    uint16_t offset, total, len;
    const uint8_t *data;
    (void)gp_sensors_unpack(frame, gp_mission_table.read_mask, &tick, &flags, sensors);
    if (gp_command_unpack(frame, NULL, &command) == GP_FRAME_OK) {
        /* a COMMAND read whole packs whole again and reads back the same */
        uint8_t payload[GP_COMMAND_MAX_SIZE];
        gp_frame repacked = {GP_MSG_COMMAND, 0, 0, 0, payload};
        repacked.length = (uint16_t)gp_command_pack(&command, NULL, payload);
        if (gp_command_unpack(&repacked, NULL, &again) != GP_FRAME_OK
            || memcmp(&command, &again, sizeof command) != 0) {
            abort();
        }
    }
    if (gp_plan_piece_unpack(frame, &offset, &total, &data, &len) == GP_FRAME_OK
        && (data < frame->payload || data + len > frame->payload + frame->length)) {
        abort(); /* the piece must lie inside the payload */
    }
}

/* The reader decodes frames in the buffer it is fed: feed it a copy. */
static void read_line(const uint8_t *input, size_t size)
{
    static uint8_t line[1 << 16];
    gp_frame_reader reader = {0};
    gp_frame frame;
    size = size < sizeof line ? size : sizeof line;
    memcpy(line, input, size);
    uint8_t *data = line;
    while (size > 0) {
        size_t used = 0;
        int result = gp_frame_reader_feed(&reader, data, size, &used, &frame);
        if (used == 0 || used > size) {
            abort(); /* the reader must make progress and stay inside its input */
        }
        if (result == GP_FRAME_OK) {
            unpack_payloads(&frame);
        }
        data += used;
        size -= used;
    }
}

static void decode_packet(const uint8_t *packet, size_t n)
{
    uint8_t wire[GP_MAX_PACKET + 2], parsed[GP_MAX_PACKET + 2];
    uint8_t rebuilt[GP_MAX_FRAME];
    if (n > GP_MAX_PACKET - 2) {
        n = GP_MAX_PACKET - 2;
    }
    memcpy(wire + 1, packet, n);
    uint16_t crc = gp_crc16(wire + 1, n);
    wire[n + 1] = (uint8_t)(crc >> 8);
    wire[n + 2] = (uint8_t)crc;
    size_t wire_len = gp_cobs_encode(wire, n + 2);

    gp_frame frame;
    memcpy(parsed, wire, wire_len);  /* parsing decodes in place */
    if (gp_frame_parse(parsed, wire_len, &frame) == GP_FRAME_OK) {
        unpack_payloads(&frame);
        size_t rebuilt_len = gp_frame_build(frame.type, frame.seq, frame.ack, frame.payload,
                                            frame.length, rebuilt);
        /* gp_frame_build appends the delimiter */
        if (rebuilt_len != wire_len + 1 || memcmp(rebuilt, wire, wire_len) != 0) {
            abort();
        }
    }
    uint8_t line[GP_MAX_PACKET + 3];
    memcpy(line, wire, wire_len);
    line[wire_len] = 0;
    read_line(line, wire_len + 1);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size == 0) {
        return 0;
    }
    if (data[0] & 1) {
        read_line(data + 1, size - 1);
    } else {
        decode_packet(data + 1, size - 1);
    }
    return 0;
}
