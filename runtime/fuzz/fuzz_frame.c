/* libFuzzer harness for the frame decoder (docs/protocol.md).
 *
 * Input byte 0, low bit clear: the rest is a packet (version, type, seq, ack, length,
 * payload) to which the harness appends its CRC-16, then COBS-encodes it, so the fuzzer
 * explores what lies behind the checksum: version, length and type checks and the
 * payload unpackers. A packet the decoder accepts must build back to the same wire
 * bytes. Low bit set: the rest goes to the frame reader raw (delimiters, overlong runs,
 * bad COBS, bad CRCs), as a corrupted serial line delivers it.
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
    double sensors[GP_N_SENSORS];
    gp_command command;
    uint16_t offset, total, len;
    const uint8_t *data;
    (void)gp_sensors_unpack(frame, &tick, sensors);
    (void)gp_command_unpack(frame, &command);
    if (gp_plan_piece_unpack(frame, &offset, &total, &data, &len) == GP_FRAME_OK
        && (data < frame->payload || data + len > frame->payload + frame->length)) {
        abort(); /* the piece must lie inside the payload */
    }
}

static void read_line(const uint8_t *data, size_t size)
{
    gp_frame_reader reader = {0};
    gp_frame frame;
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
    uint8_t framed[GP_MAX_PACKET + 2];
    uint8_t wire[2 * GP_MAX_PACKET + 8];
    uint8_t rebuilt[2 * GP_MAX_PACKET + 8];
    if (n > GP_MAX_PACKET - 2) {
        n = GP_MAX_PACKET - 2;
    }
    memcpy(framed, packet, n);
    uint16_t crc = gp_crc16(framed, n);
    framed[n] = (uint8_t)(crc >> 8);
    framed[n + 1] = (uint8_t)crc;
    size_t wire_len = gp_cobs_encode(framed, n + 2, wire);

    gp_frame frame;
    if (gp_frame_parse(wire, wire_len, &frame) == GP_FRAME_OK) {
        unpack_payloads(&frame);
        size_t rebuilt_len = gp_frame_build(frame.type, frame.seq, frame.ack, frame.payload,
                                            frame.length, rebuilt);
        /* gp_frame_build appends the delimiter */
        if (rebuilt_len != wire_len + 1 || memcmp(rebuilt, wire, wire_len) != 0) {
            abort();
        }
    }
    wire[wire_len] = 0;
    read_line(wire, wire_len + 1);
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
