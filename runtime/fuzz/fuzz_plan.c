/* libFuzzer harness for the plan reader (docs/plan-format.md), against the Fig. 2
 * mission table (tests/fig2_mission.c).
 *
 * An input whose last line does not start with "crc32 " is a plan up to its checksum
 * line: the harness appends "crc32 HEX8" with the right CRC-32, so the fuzzer reaches
 * every field behind the checksum. An input that has its own crc32 line goes to the
 * reader as it is. A plan the reader accepts must obey the format's ranges, and its
 * schedule is evaluated at a few times into each state.
 *
 * Each input is read a second time as a signed plan, against a key: unless it ends in its
 * own `hmac` line, the harness appends `seq N` and the right `hmac` tag, so the fuzzer
 * reaches the reader behind the signature as well as the signature's own lines. A plan
 * accepted with the key must be signed with a sequence number from 1.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gp_crc.h"
#include "gp_plan.h"
#include "gp_sha256.h"

static char text[GP_MAX_PLAN_BYTES + 128];
static gp_plan plan;

/* The last line of `data` starts with `word` (with its space). */
static int last_line_is(const char *data, size_t size, const char *word)
{
    size_t start = size, n = strlen(word);
    if (start > 0 && data[start - 1] == '\n') {
        start--;
    }
    while (start > 0 && data[start - 1] != '\n') {
        start--;
    }
    return size - start >= n && memcmp(data + start, word, n) == 0;
}

/* Append `seq N` and the `hmac` line that `key` gives; @return the new length. */
static size_t sign(size_t len, unsigned long seq, const uint8_t *key)
{
    len += (size_t)snprintf(text + len, sizeof text - len, "seq %lu\n", seq);
    gp_hmac_sha256 mac;
    uint8_t tag[GP_SHA256_SIZE];
    gp_hmac_sha256_init(&mac, key, GP_PLAN_KEY_BYTES);
    gp_hmac_sha256_update(&mac, text, len);
    gp_hmac_sha256_final(&mac, tag);
    len += (size_t)snprintf(text + len, sizeof text - len, "hmac ");
    for (int i = 0; i < GP_SHA256_SIZE; i++) {
        len += (size_t)snprintf(text + len, sizeof text - len, "%02x", tag[i]);
    }
    return len + (size_t)snprintf(text + len, sizeof text - len, "\n");
}

static void check_accepted(const gp_mission *mission)
{
    if (plan.n_states != mission->n_states || !(plan.budget_j >= 0) || !(plan.predicted_j >= 0)
        || plan.n_components == 0 || plan.n_components > GP_MAX_PLAN_COMPONENTS) {
        abort();
    }
    for (unsigned s = 0; s < plan.n_states; s++) {
        const gp_plan_state *ps = &plan.states[s];
        double shares = 0;
        if (!(ps->cycle_s > 0) || ps->n_sensors > GP_MAX_PLAN_SENSORS
            || ps->n_profiles == 0 || ps->n_profiles > GP_MAX_PROFILE_ALTERNATIVES) {
            abort();
        }
        for (unsigned i = 0; i < ps->n_sensors; i++) {
            const gp_plan_sensor *sensor = &ps->sensors[i];
            if (!(sensor->period_s > 0) || !(sensor->on_s >= 0 && sensor->on_s <= sensor->period_s)) {
                abort();
            }
        }
        for (unsigned i = 0; i < ps->n_profiles; i++) {
            const gp_plan_profile *profile = &ps->profiles[i];
            if (!(profile->share >= 0 && profile->share <= 1) || !(profile->pitch_rad > 0)
                || !(profile->ballast_cc > 0) || !(profile->speed_mps > 0)) {
                abort();
            }
            shares += profile->share;
        }
        if (fabs(shares - 1) > 1e-5) {
            abort();
        }
        static const double times_s[] = {0, 0.5, 59.9, 600, 1e6, 4e9};
        for (unsigned t = 0; t < sizeof times_s / sizeof times_s[0]; t++) {
            gp_schedule_now now;
            gp_schedule(&mission->states[s], ps, times_s[t], 100.0, &now);
            if (now.profile >= ps->n_profiles) {
                abort();
            }
        }
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const gp_mission *mission = &gp_mission_table;
    size_t len = size < GP_MAX_PLAN_BYTES + 1 ? size : GP_MAX_PLAN_BYTES + 1;
    memcpy(text, data, len);
    int signed_input = last_line_is(text, len, "hmac ");
    if (!signed_input && !last_line_is(text, len, "crc32 ") && len <= GP_MAX_PLAN_BYTES) {
        uint32_t crc = gp_crc32(0, (const uint8_t *)text, len);
        len += (size_t)snprintf(text + len, sizeof text - len, "crc32 %08x\n", (unsigned)crc);
    }
    char error[GP_PLAN_ERROR_LEN];
    memset(error, 0, sizeof error);
    if (gp_plan_read(text, len, mission, NULL, &plan, error) == 0) {
        check_accepted(mission);
    } else if (error[0] == '\0' || memchr(error, '\0', sizeof error) == NULL) {
        abort(); /* a rejection always says why, in one terminated line */
    }
    static gp_plan_auth auth;
    for (int i = 0; i < GP_PLAN_KEY_BYTES; i++) {
        auth.key[i] = (uint8_t)(0xA5 ^ i);
    }
    if (!signed_input && len <= GP_MAX_PLAN_BYTES) {
        len = sign(len, 1 + size % 4000000000u, auth.key);
    }
    memset(error, 0, sizeof error);
    if (gp_plan_read(text, len, mission, &auth, &plan, error) == 0) {
        if (!plan.is_signed || plan.seq < 1) {
            abort();  /* a keyed reader flies signed plans only */
        }
        check_accepted(mission);
    } else if (error[0] == '\0' || memchr(error, '\0', sizeof error) == NULL) {
        abort();
    }
    return 0;
}
