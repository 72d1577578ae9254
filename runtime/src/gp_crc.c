/* Table-driven CRCs: framing costs more than the mission's step, so the CRC-16 takes
 * two bytes per round (two lookups); the CRC-32 of plans and checkpoints one byte.
 * The tables are filled on first use (static memory, nothing allocated). */
#include "gp_crc.h"

static uint16_t crc16_table[256];      /* one byte through the register */
static uint16_t crc16_table_hi[256];   /* a byte followed by a zero byte */
static uint32_t crc32_table[256];
static int tables_ready;

static void fill_tables(void)
{
    for (uint32_t i = 0; i < 256; i++) {
        uint16_t c16 = (uint16_t)(i << 8);
        uint32_t c32 = i;
        for (int bit = 0; bit < 8; bit++) {
            c16 = (c16 & 0x8000u) ? (uint16_t)((c16 << 1) ^ 0x1021u) : (uint16_t)(c16 << 1);
            c32 = (c32 & 1u) ? (c32 >> 1) ^ 0xEDB88320u : c32 >> 1;
        }
        crc16_table[i] = c16;
        crc32_table[i] = c32;
    }
    /* The CRC is linear, so two bytes (hi, lo) through the register give
     * table_hi[hi] ^ table[lo] with table_hi[i] = (table[i] << 8) ^ table[table[i] >> 8]. */
    for (uint32_t i = 0; i < 256; i++) {
        crc16_table_hi[i] = (uint16_t)((crc16_table[i] << 8) ^ crc16_table[crc16_table[i] >> 8]);
    }
    tables_ready = 1;
}

uint16_t gp_crc16(const uint8_t *data, size_t len)
{
    if (!tables_ready) {
        fill_tables();
    }
    uint16_t crc = 0xFFFFu;
    size_t i = 0;
    for (; i + 1 < len; i += 2) {
        crc ^= (uint16_t)((data[i] << 8) | data[i + 1]);
        crc = crc16_table_hi[crc >> 8] ^ crc16_table[crc & 0xFFu];
    }
    if (i < len) {
        crc = (uint16_t)((crc << 8) ^ crc16_table[((crc >> 8) ^ data[i]) & 0xFFu]);
    }
    return crc;
}

uint32_t gp_crc32(uint32_t crc, const uint8_t *data, size_t len)
{
    if (!tables_ready) {
        fill_tables();
    }
    crc = ~crc;
    for (size_t i = 0; i < len; i++) {
        crc = (crc >> 8) ^ crc32_table[(crc ^ data[i]) & 0xFFu];
    }
    return ~crc;
}
