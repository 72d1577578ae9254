/* libFuzzer harness for the plan reader (docs/plan-format.md), against the Fig. 2
 * mission table (tests/fig2_mission.c).
 *
 * An input whose last line does not start with "crc32 " is a plan up to its checksum
 * line: the harness appends "crc32 HEX8" with the right CRC-32, so the fuzzer reaches
 * every field behind the checksum. An input that has its own crc32 line goes to the
 * reader as it is. A plan the reader accepts must obey the format's ranges, and its
 * schedule is evaluated at a few times into each state.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gp_crc.h"
#include "gp_plan.h"

static char text[GP_MAX_PLAN_BYTES + 32];
static gp_plan plan;

static int has_crc_line(const uint8_t *data, size_t size)
{
    size_t start = size;
    if (start > 0 && data[start - 1] == '\n') {
        start--;
    }
    while (start > 0 && data[start - 1] != '\n') {
        start--;
    }
    return size - start >= 6 && memcmp(data + start, "crc32 ", 6) == 0;
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
    if (!has_crc_line(data, len) && len <= GP_MAX_PLAN_BYTES) {
        uint32_t crc = gp_crc32(0, (const uint8_t *)text, len);
        len += (size_t)snprintf(text + len, sizeof text - len, "crc32 %08x\n", (unsigned)crc);
    }
    char error[GP_PLAN_ERROR_LEN];
    memset(error, 0, sizeof error);
    if (gp_plan_read(text, len, mission, &plan, error) == 0) {
        check_accepted(mission);
    } else if (error[0] == '\0' || memchr(error, '\0', sizeof error) == NULL) {
        abort(); /* a rejection always says why, in one terminated line */
    }
    return 0;
}
