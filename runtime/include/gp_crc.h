/**
 * @file gp_crc.h
 * @brief Checksums of the link (CRC-16/CCITT-FALSE) and of plan and checkpoint files
 *        (CRC-32/ISO-HDLC, the one of zlib).
 */
#ifndef GP_CRC_H
#define GP_CRC_H

#include <stddef.h>
#include <stdint.h>

/** @brief CRC-16/CCITT-FALSE: poly 0x1021, init 0xFFFF, not reflected, xorout 0. */
uint16_t gp_crc16(const uint8_t *data, size_t len);

/**
 * @brief CRC-32/ISO-HDLC, continued from `crc` (start with 0).
 * @return the CRC of everything fed so far
 */
uint32_t gp_crc32(uint32_t crc, const uint8_t *data, size_t len);

#endif /* GP_CRC_H */
