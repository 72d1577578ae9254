/**
 * @file gp_sha256.h
 * @brief SHA-256 (FIPS 180-4) and HMAC-SHA256 (RFC 2104), for signed plans
 *        (docs/plan-format.md). Streaming, no allocation, the context on the caller's
 *        stack or in static memory.
 */
#ifndef GP_SHA256_H
#define GP_SHA256_H

#include <stddef.h>
#include <stdint.h>

#define GP_SHA256_SIZE 32   /**< bytes of a digest */
#define GP_SHA256_BLOCK 64  /**< bytes of a block */

typedef struct {
    uint32_t h[8];                   /**< the chaining value */
    uint64_t bytes;                  /**< message bytes fed so far */
    uint8_t block[GP_SHA256_BLOCK];  /**< bytes not yet compressed */
    size_t used;                     /**< of `block` */
} gp_sha256;

/** @brief Start a digest. */
void gp_sha256_init(gp_sha256 *ctx);

/** @brief Feed `len` bytes. */
void gp_sha256_update(gp_sha256 *ctx, const void *data, size_t len);

/** @brief Pad, and write the digest to `out` (GP_SHA256_SIZE bytes). */
void gp_sha256_final(gp_sha256 *ctx, uint8_t out[GP_SHA256_SIZE]);

typedef struct {
    gp_sha256 inner, outer;
} gp_hmac_sha256;

/** @brief Start an HMAC-SHA256 with a key of any length (a longer one than a block
 *         is hashed first, as RFC 2104 says). */
void gp_hmac_sha256_init(gp_hmac_sha256 *ctx, const uint8_t *key, size_t key_len);

/** @brief Feed `len` bytes of the message. */
void gp_hmac_sha256_update(gp_hmac_sha256 *ctx, const void *data, size_t len);

/** @brief Write the tag to `out` (GP_SHA256_SIZE bytes). */
void gp_hmac_sha256_final(gp_hmac_sha256 *ctx, uint8_t out[GP_SHA256_SIZE]);

/** @brief Compare two tags in time that does not depend on where they differ;
 *  @return 1 equal, 0 not. */
int gp_tags_equal(const uint8_t a[GP_SHA256_SIZE], const uint8_t b[GP_SHA256_SIZE]);

#endif /* GP_SHA256_H */
