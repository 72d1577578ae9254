/* libFuzzer harness for the plan-update applier (docs/plan-update.md), against the Fig. 2
 * mission table (tests/fig2_mission.c) holding the good plan of tests/fig2_plan.h, signed
 * as plan 3.
 *
 * An input that starts with "GU" goes to the applier as it is (the tag then rarely
 * matches: the form's checks are fuzzed). Any other input is the changes of an update:
 * the harness puts the header of an update 3 -> 4 in front (the first byte of the input
 * is its count of changes), the result hash of the plan those changes make, and the
 * right tag after it, so the fuzzer reaches everything behind the signature. The applier
 * must always say why it refuses; an update it applies must make a plan the strict
 * reader accepts, as plan 4, whose file is the one the hash named.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../tests/fig2_plan.h"
#include "gp_crc.h"
#include "gp_sha256.h"
#include "gp_update.h"

static char held[GP_MAX_PLAN_BYTES];
static size_t held_len;
static char out[GP_MAX_PLAN_BYTES];
static uint8_t update[GP_MAX_UPDATE_BYTES + 64];
static gp_plan plan, check;
static gp_plan_auth auth;

static void sha(const void *data, size_t len, uint8_t digest[GP_SHA256_SIZE])
{
    gp_sha256 ctx;
    gp_sha256_init(&ctx);
    gp_sha256_update(&ctx, data, len);
    gp_sha256_final(&ctx, digest);
}

static void tag(const uint8_t *data, size_t len, uint8_t *out_tag)
{
    gp_hmac_sha256 mac;
    gp_hmac_sha256_init(&mac, auth.key, GP_PLAN_KEY_BYTES);
    gp_hmac_sha256_update(&mac, data, len);
    gp_hmac_sha256_final(&mac, out_tag);
}

/* The held plan: GOOD_BODY signed as plan 3. */
static void hold(void)
{
    if (held_len) {
        return;
    }
    for (int i = 0; i < GP_PLAN_KEY_BYTES; i++) {
        auth.key[i] = (uint8_t)(0x5A ^ i);
    }
    size_t len = strlen(GOOD_BODY);
    memcpy(held, GOOD_BODY, len);
    len += (size_t)snprintf(held + len, sizeof held - len, "crc32 %08lx\nseq 3\n",
                            (unsigned long)gp_crc32(0, (const uint8_t *)held, len));
    uint8_t t[GP_SHA256_SIZE];
    tag((const uint8_t *)held, len, t);
    len += (size_t)snprintf(held + len, sizeof held - len, "hmac ");
    for (int i = 0; i < GP_SHA256_SIZE; i++) {
        len += (size_t)snprintf(held + len, sizeof held - len, "%02x", t[i]);
    }
    held_len = len + (size_t)snprintf(held + len, sizeof held - len, "\n");
    char error[GP_PLAN_ERROR_LEN];
    if (gp_plan_read(held, held_len, &gp_mission_table, &auth, &plan, error) != 0) {
        abort();
    }
    auth.last_seq = 3;
    memcpy(auth.last_tag, plan.tag, sizeof plan.tag);
}

static gp_update_status apply(size_t len, size_t *new_len, char *message)
{
    memset(message, 0, GP_UPDATE_MESSAGE_LEN);
    gp_update_status status = gp_update_apply(update, len, held, held_len, &auth,
                                              &gp_mission_table, out, new_len, &plan, message);
    if (message[0] == '\0' || memchr(message, '\0', GP_UPDATE_MESSAGE_LEN) == NULL
        || status > GP_UPDATE_NOT_STORED) {
        abort();  /* every verdict says what became of the update, in one terminated line */
    }
    return status;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char message[GP_UPDATE_MESSAGE_LEN];
    size_t new_len = 0;
    hold();
    if (size >= 2 && data[0] == 'G' && data[1] == 'U') {
        size_t len = size < sizeof update ? size : sizeof update;
        memcpy(update, data, len);
        if (apply(len, &new_len, message) == GP_UPDATE_APPLIED) {
            abort();  /* no input can carry the right tag of a key it does not know */
        }
        return 0;
    }
    size_t n = size > 1 ? size - 1 : 0;
    if (GP_UPDATE_HEADER_BYTES + n + GP_SHA256_SIZE > GP_MAX_UPDATE_BYTES) {
        n = GP_MAX_UPDATE_BYTES - GP_UPDATE_HEADER_BYTES - GP_SHA256_SIZE;
    }
    uint8_t digest[GP_SHA256_SIZE];
    sha(held, held_len, digest);
    memcpy(update, "GU\x01\x03\x00\x00\x00\x04\x00\x00\x00", 11);
    memcpy(update + 11, digest, GP_UPDATE_HASH_BYTES);
    memset(update + 19, 0, GP_UPDATE_HASH_BYTES);
    update[27] = size ? data[0] : 0;
    memcpy(update + GP_UPDATE_HEADER_BYTES, data + (size ? 1 : 0), n);
    size_t len = GP_UPDATE_HEADER_BYTES + n;
    tag(update, len, update + len);
    /* a first pass with a result hash of zeros finds the plan the changes make ... */
    gp_update_status status = apply(len + GP_SHA256_SIZE, &new_len, message);
    if (status == GP_UPDATE_APPLIED) {
        abort();
    }
    if (strstr(message, "its hash differs") == NULL) {
        return 0;
    }
    /* ... a second names it, as a shore would: applied, or refused by the reader */
    sha(out, new_len, digest);
    memcpy(update + 19, digest, GP_UPDATE_HASH_BYTES);
    tag(update, len, update + len);
    status = apply(len + GP_SHA256_SIZE, &new_len, message);
    if (status == GP_UPDATE_APPLIED) {
        static gp_plan_auth before;
        char error[GP_PLAN_ERROR_LEN];
        before = auth;
        if (plan.seq != 4 || plan.n_states != gp_mission_table.n_states
            || gp_plan_read(out, new_len, &gp_mission_table, &before, &check, error) != 0) {
            abort();  /* what is flown is a signed plan the reader accepts, as plan 4 */
        }
    } else if (status != GP_UPDATE_BAD_PLAN) {
        abort();
    }
    return 0;
}
