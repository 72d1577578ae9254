/* CRCs by slicing (Kounavis and Berry's slicing-by-N): N table lookups take N bytes
 * through the register at once. Table k holds the register's change for a byte
 * followed by k zero bytes. The link's CRC-16 runs twice a tick over frames of 20 to 40
 * bytes: eight bytes a round (4 KiB of tables); the CRC-32 of a checkpoint record, a
 * few times a minute: four (4 KiB). The tables are filled on first use: static
 * memory, nothing allocated. */
#include "gp_crc.h"

static uint16_t crc16_table[8][256];  /* not reflected: the register shifts left */
static uint32_t crc32_table[4][256];  /* reflected: the register shifts right */
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
        crc16_table[0][i] = c16;
        crc32_table[0][i] = c32;
    }
    for (int k = 1; k < 8; k++) {  /* one more zero byte through the register */
        for (uint32_t i = 0; i < 256; i++) {
            uint16_t c16 = crc16_table[k - 1][i];
            crc16_table[k][i] = (uint16_t)((c16 << 8) ^ crc16_table[0][c16 >> 8]);
            if (k < 4) {
                uint32_t c32 = crc32_table[k - 1][i];
                crc32_table[k][i] = (c32 >> 8) ^ crc32_table[0][c32 & 0xFFu];
            }
        }
    }
    tables_ready = 1;
}

uint16_t gp_crc16(const uint8_t *data, size_t len)
{
    if (!tables_ready) {
        fill_tables();
    }
    uint16_t crc = 0xFFFFu;
    const uint8_t *p = data, *end = data + len;
    for (; end - p >= 8; p += 8) {
        /* the register's two bytes meet the first two data bytes; the other six have
         * nothing to meet yet */
        crc = (uint16_t)(crc16_table[7][(crc >> 8) ^ p[0]] ^ crc16_table[6][(crc & 0xFFu) ^ p[1]]
                         ^ crc16_table[5][p[2]] ^ crc16_table[4][p[3]] ^ crc16_table[3][p[4]]
                         ^ crc16_table[2][p[5]] ^ crc16_table[1][p[6]] ^ crc16_table[0][p[7]]);
    }
    if (end - p >= 4) {  /* four of the last seven bytes at once, as above */
        crc = (uint16_t)(crc16_table[3][(crc >> 8) ^ p[0]] ^ crc16_table[2][(crc & 0xFFu) ^ p[1]]
                         ^ crc16_table[1][p[2]] ^ crc16_table[0][p[3]]);
        p += 4;
    }
    for (; p < end; p++) {
        crc = (uint16_t)((crc << 8) ^ crc16_table[0][(crc >> 8) ^ *p]);
    }
    return crc;
}

uint32_t gp_crc32(uint32_t crc, const uint8_t *data, size_t len)
{
    if (!tables_ready) {
        fill_tables();
    }
    crc = ~crc;
    const uint8_t *p = data, *end = data + len;
    for (; end - p >= 4; p += 4) {  /* bytes, not a word load: any alignment, any endianness */
        uint32_t x = crc ^ ((uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16)
                            | ((uint32_t)p[3] << 24));
        crc = crc32_table[3][x & 0xFFu] ^ crc32_table[2][(x >> 8) & 0xFFu]
            ^ crc32_table[1][(x >> 16) & 0xFFu] ^ crc32_table[0][x >> 24];
    }
    for (; p < end; p++) {
        crc = (crc >> 8) ^ crc32_table[0][(crc ^ *p) & 0xFFu];
    }
    return ~crc;
}
