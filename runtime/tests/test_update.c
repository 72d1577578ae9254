/* Plan updates (docs/plan-update.md) against the Fig. 2 table: an update makes its change
 * in the plan file's text and signs the result; every other update is refused, and the
 * message says why, in the words gliderplan.planner.update uses.
 *
 *   held plan (seq 3) --update 3->4--> new plan (seq 4)
 *        |                                 |
 *        +-- forged, stale, replayed,      +-- the same update again: DUPLICATE
 *            for another plan, out of
 *            order, malformed: refused, the plan in force stays
 */
#include <stdio.h>
#include <string.h>

#include "fig2_plan.h"
#include "gp_crc.h"
#include "gp_sha256.h"
#include "gp_test.h"
#include "gp_update.h"

#define SENSOR_TEMP_LINE 21  /* "sensor temp 60 15" of GOOD_BODY */
#define PROFILE_S2_LINE 22   /* "profile 0 1 0.4 200 0.3" */
#define MAX_TEST_CHANGES 8

static const uint8_t KEY[GP_PLAN_KEY_BYTES] = {
    0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15,
    16, 17, 18, 19, 20, 21, 22, 23, 24, 25, 26, 27, 28, 29, 30, 31};

typedef struct {
    uint8_t field;
    uint32_t line;
    int64_t mantissa;
    int exponent;
} test_change;

static char held[GP_MAX_PLAN_BYTES];
static size_t held_len;
static char expected[GP_MAX_PLAN_BYTES];
static size_t expected_len;
static char out[GP_MAX_PLAN_BYTES];
static gp_plan plan;

/* `body` with its crc32, `seq` and hmac lines, signed with KEY, into `dst`. */
static size_t sign_body(const char *body, unsigned long seq, char *dst)
{
    size_t len = strlen(body);
    memcpy(dst, body, len);
    len += (size_t)sprintf(dst + len, "crc32 %08lx\nseq %lu\n",
                           (unsigned long)gp_crc32(0, (const uint8_t *)body, strlen(body)),
                           seq);
    gp_hmac_sha256 mac;
    uint8_t tag[GP_SHA256_SIZE];
    gp_hmac_sha256_init(&mac, KEY, sizeof KEY);
    gp_hmac_sha256_update(&mac, dst, len);
    gp_hmac_sha256_final(&mac, tag);
    len += (size_t)sprintf(dst + len, "hmac ");
    for (int i = 0; i < GP_SHA256_SIZE; i++) {
        len += (size_t)sprintf(dst + len, "%02x", tag[i]);
    }
    return len + (size_t)sprintf(dst + len, "\n");
}

/* `body` (a static buffer of GP_MAX_PLAN_BYTES) with the first `from` replaced by `to`. */
static void edit(char *body, const char *from, const char *to)
{
    static char rest[GP_MAX_PLAN_BYTES];
    char *at = strstr(body, from);
    CHECK(at != NULL);
    if (at == NULL) {
        return;
    }
    snprintf(rest, sizeof rest, "%s", at + strlen(from));
    snprintf(at, GP_MAX_PLAN_BYTES - (size_t)(at - body), "%s%s", to, rest);
}

/* GOOD_BODY with `from` replaced by `to`, signed as plan `seq` into `dst`. */
static size_t signed_variant(const char *from, const char *to, unsigned long seq, char *dst)
{
    static char body[GP_MAX_PLAN_BYTES];
    snprintf(body, sizeof body, "%s", GOOD_BODY);
    edit(body, from, to);
    return sign_body(body, seq, dst);
}

static void hash8(const char *text, size_t len, uint8_t *out8)
{
    gp_sha256 sha;
    uint8_t digest[GP_SHA256_SIZE];
    gp_sha256_init(&sha);
    gp_sha256_update(&sha, text, len);
    gp_sha256_final(&sha, digest);
    memcpy(out8, digest, GP_UPDATE_HASH_BYTES);
}

static size_t varint(uint64_t n, uint8_t *p)
{
    size_t i = 0;
    do {
        p[i] = (uint8_t)(n & 0x7F);
        n >>= 7;
        p[i] |= n ? 0x80 : 0;
        i++;
    } while (n);
    return i;
}

static void put32(uint8_t *p, uint32_t v)
{
    for (int i = 0; i < 4; i++) {
        p[i] = (uint8_t)(v >> (8 * i));
    }
}

/* An update base_seq -> new_seq of `n` changes, its result hash that of `result` (NULL:
 * zeros), signed with `key`; @return its length. */
static size_t make_update(uint32_t base_seq, uint32_t new_seq, const char *base, size_t base_len,
                          const char *result, size_t result_len, const test_change *changes,
                          int n, const uint8_t *key, uint8_t *u)
{
    memcpy(u, "GU", 2);
    u[2] = GP_UPDATE_FORMAT_VERSION;
    put32(u + 3, base_seq);
    put32(u + 7, new_seq);
    hash8(base, base_len, u + 11);
    memset(u + 19, 0, GP_UPDATE_HASH_BYTES);
    if (result) {
        hash8(result, result_len, u + 19);
    }
    u[27] = (uint8_t)n;
    size_t at = GP_UPDATE_HEADER_BYTES;
    uint32_t line = 0;
    for (int i = 0; i < n; i++) {
        const test_change *c = &changes[i];
        u[at++] = c->field;
        at += varint(c->line - line, u + at);
        uint64_t zigzag = c->mantissa >= 0 ? 2 * (uint64_t)c->mantissa
                                           : 2 * (uint64_t)(-c->mantissa) - 1;
        at += varint(zigzag, u + at);
        u[at++] = (uint8_t)(int8_t)c->exponent;
        line = c->line;
    }
    gp_hmac_sha256 mac;
    gp_hmac_sha256_init(&mac, key, GP_PLAN_KEY_BYTES);
    gp_hmac_sha256_update(&mac, u, at);
    gp_hmac_sha256_final(&mac, u + at);
    return at + GP_SHA256_SIZE;
}

/* The plan in force: GOOD_BODY signed as plan 3, and the key with its place. */
static void hold_plan_3(gp_plan_auth *auth)
{
    held_len = sign_body(GOOD_BODY, 3, held);
    memcpy(auth->key, KEY, sizeof KEY);
    char error[GP_PLAN_ERROR_LEN];
    auth->last_seq = 0;
    CHECK_INT(gp_plan_read(held, held_len, &gp_mission_table, auth, &plan, error), 0);
    auth->last_seq = 3;
    memcpy(auth->last_tag, plan.tag, sizeof plan.tag);
}

static gp_update_status apply(const uint8_t *u, size_t len, const gp_plan_auth *auth,
                              char *message, size_t *new_len)
{
    return gp_update_apply(u, len, held, held_len, auth, &gp_mission_table, out, new_len,
                           &plan, message);
}

/* 3 -> 4: temp's on-time in s2 becomes 42.5 s. */
static const test_change TEMP_ON = {GP_UF_SENSOR_ON, SENSOR_TEMP_LINE, 425, -1};

void test_update_should_make_its_change_and_sign_the_result(void)
{
    gp_plan_auth auth;
    uint8_t u[GP_MAX_UPDATE_BYTES];
    char message[GP_UPDATE_MESSAGE_LEN];
    size_t new_len = 0;
    hold_plan_3(&auth);
    expected_len = signed_variant("sensor temp 60 15", "sensor temp 60 42.5", 4, expected);
    size_t len = make_update(3, 4, held, held_len, expected, expected_len, &TEMP_ON, 1, KEY, u);
    CHECK_INT(apply(u, len, &auth, message, &new_len), GP_UPDATE_APPLIED);
    CHECK_CONTAINS(message, "ok: plan 4 in force");
    CHECK_INT(new_len, expected_len);
    CHECK(memcmp(out, expected, expected_len) == 0);
    CHECK_INT(plan.seq, 4);
    CHECK_NEAR(plan.states[1].sensors[1].on_s, 42.5, 0);

    /* two changes on one line and one on the next: share stays 1, pitch and ballast move */
    static const test_change PROFILE[] = {{GP_UF_PROFILE_PITCH, PROFILE_S2_LINE, 45, -2},
                                          {GP_UF_PROFILE_BALLAST, PROFILE_S2_LINE, 1825, -1},
                                          {GP_UF_STATE_CYCLE, PROFILE_S2_LINE + 2, 9, 2}};
    hold_plan_3(&auth);
    static char body[GP_MAX_PLAN_BYTES];
    snprintf(body, sizeof body, "%s", GOOD_BODY);
    edit(body, "profile 0 1 0.4 200 0.3", "profile 0 1 0.45 182.5 0.3");
    edit(body, "state s3 300 600", "state s3 300 900");
    expected_len = sign_body(body, 4, expected);
    len = make_update(3, 4, held, held_len, expected, expected_len, PROFILE, 3, KEY, u);
    CHECK_INT(apply(u, len, &auth, message, &new_len), GP_UPDATE_APPLIED);
    CHECK(new_len == expected_len && memcmp(out, expected, expected_len) == 0);
    CHECK_NEAR(plan.states[1].profiles[0].ballast_cc, 182.5, 0);
    CHECK_NEAR(plan.states[2].cycle_s, 900, 0);
}

void test_update_should_refuse_forged_stale_and_replayed_updates_and_other_plans(void)
{
    gp_plan_auth auth;
    uint8_t u[GP_MAX_UPDATE_BYTES];
    char message[GP_UPDATE_MESSAGE_LEN];
    size_t new_len = 0, len;
    static const uint8_t OTHER_KEY[GP_PLAN_KEY_BYTES] = {7};
    hold_plan_3(&auth);
    expected_len = signed_variant("sensor temp 60 15", "sensor temp 60 42.5", 4, expected);

    CHECK_INT(gp_update_apply(u, 0, held, held_len, NULL, &gp_mission_table, out, &new_len,
                              &plan, message), GP_UPDATE_NO_KEY);
    CHECK_CONTAINS(message, "no key is provisioned on this vehicle");

    len = make_update(3, 4, held, held_len, expected, expected_len, &TEMP_ON, 1, OTHER_KEY, u);
    CHECK_INT(apply(u, len, &auth, message, &new_len), GP_UPDATE_FORGED);
    CHECK_CONTAINS(message, "the signature does not match");
    len = make_update(3, 4, held, held_len, expected, expected_len, &TEMP_ON, 1, KEY, u);
    u[len - 1] ^= 1;
    CHECK_INT(apply(u, len, &auth, message, &new_len), GP_UPDATE_FORGED);
    u[len - 1] ^= 1;
    u[8] ^= 0x10;  /* the new seq, changed after signing */
    CHECK_INT(apply(u, len, &auth, message, &new_len), GP_UPDATE_FORGED);

    len = make_update(2, 3, held, held_len, expected, expected_len, &TEMP_ON, 1, KEY, u);
    CHECK_INT(apply(u, len, &auth, message, &new_len), GP_UPDATE_STALE);
    CHECK_CONTAINS(message, "update to plan 3 is not newer than plan 3 in force: replayed or "
                            "stale");
    len = make_update(1, 2, held, held_len, expected, expected_len, &TEMP_ON, 1, KEY, u);
    CHECK_INT(apply(u, len, &auth, message, &new_len), GP_UPDATE_STALE);

    len = make_update(2, 4, held, held_len, expected, expected_len, &TEMP_ON, 1, KEY, u);
    CHECK_INT(apply(u, len, &auth, message, &new_len), GP_UPDATE_NOT_HELD);
    CHECK_CONTAINS(message, "the update was made against plan 2; plan 3 is in force");
    len = make_update(3, 4, expected, expected_len, expected, expected_len, &TEMP_ON, 1, KEY, u);
    CHECK_INT(apply(u, len, &auth, message, &new_len), GP_UPDATE_NOT_HELD);
    CHECK_CONTAINS(message, "its hash differs from the plan in force");
    len = make_update(5, 6, held, held_len, expected, expected_len, &TEMP_ON, 1, KEY, u);
    CHECK_INT(apply(u, len, &auth, message, &new_len), GP_UPDATE_OUT_OF_ORDER);
    CHECK_CONTAINS(message, "an update before it has not arrived");
    CHECK_INT(gp_update_apply(u, len, NULL, 0, &auth, &gp_mission_table, out, &new_len, &plan,
                              message), GP_UPDATE_NOT_HELD);
    CHECK_CONTAINS(message, "no signed plan is in force");

    /* applied, then sent again: the plan in force is its result */
    len = make_update(3, 4, held, held_len, expected, expected_len, &TEMP_ON, 1, KEY, u);
    CHECK_INT(apply(u, len, &auth, message, &new_len), GP_UPDATE_APPLIED);
    memcpy(held, out, new_len);
    held_len = new_len;
    auth.last_seq = 4;
    CHECK_INT(apply(u, len, &auth, message, &new_len), GP_UPDATE_DUPLICATE);
    CHECK_CONTAINS(message, "update to plan 4 already applied: plan 4 is in force");
    CHECK_INT(plan.seq, 4);
}

/* An update of the good one's header and tag around `changes` (`n` bytes of them) that
 * claims `count` changes. */
static size_t raw_update(const uint8_t *changes, size_t n, int count, uint8_t *u)
{
    size_t len = make_update(3, 4, held, held_len, NULL, 0, NULL, 0, KEY, u);
    len -= GP_SHA256_SIZE;
    u[27] = (uint8_t)count;
    memcpy(u + len, changes, n);
    len += n;
    gp_hmac_sha256 mac;
    gp_hmac_sha256_init(&mac, KEY, sizeof KEY);
    gp_hmac_sha256_update(&mac, u, len);
    gp_hmac_sha256_final(&mac, u + len);
    return len + GP_SHA256_SIZE;
}

void test_update_should_refuse_malformed_updates_naming_the_change(void)
{
    gp_plan_auth auth;
    uint8_t u[2 * GP_MAX_UPDATE_BYTES];
    char message[GP_UPDATE_MESSAGE_LEN];
    size_t new_len = 0, len;
    hold_plan_3(&auth);
    static const struct {
        uint8_t bytes[16];
        size_t n;
        int count;
        gp_update_status status;
        const char *said;
    } CASES[] = {
        {{0}, 0, 1, GP_UPDATE_MALFORMED, "change 1: the update ends before it"},
        {{12, 21, 2, 0}, 4, 1, GP_UPDATE_MALFORMED, "change 1: no field has code 12"},
        {{6, 0x80, 0x80, 0x80, 0x80, 0x80, 0x80, 0x80, 0x80, 0x01}, 10, 1, GP_UPDATE_MALFORMED,
         "change 1: line: a number longer than 8 bytes"},
        {{6, 0x81, 0x80, 0x08, 2, 0}, 6, 1, GP_UPDATE_MALFORMED,
         "change 1: line: more than 65536"},
        {{6, 21, 20, 0}, 4, 1, GP_UPDATE_MALFORMED, "change 1: the value is not a canonical"},
        {{6, 21, 0, 1}, 4, 1, GP_UPDATE_MALFORMED, "change 1: the value is not a canonical"},
        {{6, 21, 2, 21}, 4, 1, GP_UPDATE_MALFORMED, "change 1: the value is not a canonical"},
        {{6, 0, 2, 0}, 4, 1, GP_UPDATE_MALFORMED, "change 1: changes must come in the order"},
        {{6, 21, 2, 0, 5, 0, 2, 0}, 8, 2, GP_UPDATE_MALFORMED,
         "change 2: changes must come in the order"},
        {{6, 21, 2}, 3, 1, GP_UPDATE_MALFORMED, "change 1: the update ends inside it"},
        {{6, 21, 2, 0, 9}, 5, 1, GP_UPDATE_MALFORMED, "1 bytes after the last change"},
        {{6, 99, 2, 0}, 4, 1, GP_UPDATE_MALFORMED, "change 1: line 99 is not in the plan's body"},
        {{6, 22, 2, 0}, 4, 1, GP_UPDATE_MALFORMED, "change 1: line 22 is no 'sensor' line"},
        {{7, 22, 4, 0}, 4, 1, GP_UPDATE_MALFORMED, "the plan it makes is not the plan it was"},
    };
    for (size_t i = 0; i < sizeof CASES / sizeof CASES[0]; i++) {
        len = raw_update(CASES[i].bytes, CASES[i].n, CASES[i].count, u);
        CHECK_INT(apply(u, len, &auth, message, &new_len), CASES[i].status);
        CHECK_CONTAINS(message, CASES[i].said);
    }
    len = make_update(3, 4, held, held_len, NULL, 0, &TEMP_ON, 1, KEY, u);
    CHECK_INT(apply(u, 2, &auth, message, &new_len), GP_UPDATE_MALFORMED);
    CHECK_CONTAINS(message, "not a plan update (2 bytes, no GU magic)");
    u[0] = 'X';
    CHECK_INT(apply(u, len, &auth, message, &new_len), GP_UPDATE_MALFORMED);
    u[0] = 'G';
    u[2] = 2;
    CHECK_INT(apply(u, len, &auth, message, &new_len), GP_UPDATE_MALFORMED);
    CHECK_CONTAINS(message, "update version 2: this vehicle reads version 1");
    CHECK_INT(apply(u, GP_MAX_UPDATE_BYTES + 1, &auth, message, &new_len), GP_UPDATE_MALFORMED);
    CHECK_CONTAINS(message, "the update has 271 bytes, more than 270");
    CHECK_INT(plan.seq, 3);  /* nothing refused touched the plan in force */
}

void test_update_should_refuse_a_plan_the_reader_refuses(void)
{
    gp_plan_auth auth;
    uint8_t u[GP_MAX_UPDATE_BYTES];
    char message[GP_UPDATE_MESSAGE_LEN];
    size_t new_len = 0;
    hold_plan_3(&auth);
    static const test_change SHARE = {GP_UF_PROFILE_SHARE, PROFILE_S2_LINE, 2, 0};
    expected_len = signed_variant("profile 0 1 0.4 200 0.3", "profile 0 2 0.4 200 0.3", 4,
                                  expected);
    size_t len = make_update(3, 4, held, held_len, expected, expected_len, &SHARE, 1, KEY, u);
    CHECK_INT(apply(u, len, &auth, message, &new_len), GP_UPDATE_BAD_PLAN);
    CHECK_CONTAINS(message, "the updated plan is refused: line 22:");
    static const test_change CLOCK = {GP_UF_STATE_CLOCK, 17, 4, 2};  /* 400 MHz */
    expected_len = signed_variant("state s2 500", "state s2 400", 4, expected);
    len = make_update(3, 4, held, held_len, expected, expected_len, &CLOCK, 1, KEY, u);
    CHECK_INT(apply(u, len, &auth, message, &new_len), GP_UPDATE_BAD_PLAN);
    CHECK_CONTAINS(message, "clock 400 MHz");
    CHECK_INT(plan.seq, 3);
}

/* Fig. 2 on a hybrid: a thruster of 1-9 W, the bounds the code generator writes. */
static const gp_mission *fig2_hybrid(void)
{
    static const gp_plan_bounds bounds = {
        .board = NULL, .max_budget_j = GP_MAX_PLAN_ENERGY_J, .min_pitch_rad = 0,
        .max_pitch_rad = 1.5707963267948966, .max_speed_mps = GP_MAX_PLAN_SPEED_MPS,
        .min_propelled_mps = 0.4, .max_propelled_mps = 0.84, .min_thrust_w = 1,
        .max_thrust_w = 9, .states = NULL};
    static gp_mission hybrid;
    hybrid = gp_mission_table;
    hybrid.unplanned_speed_mps = 0.45;
    hybrid.bounds = &bounds;
    return &hybrid;
}

void test_update_should_set_a_thrusters_power_within_its_rating(void)
{
    gp_plan_auth auth;
    uint8_t u[GP_MAX_UPDATE_BYTES];
    char message[GP_UPDATE_MESSAGE_LEN];
    size_t new_len = 0;
    const gp_mission *hybrid = fig2_hybrid();
    /* the line leaves THRUST_W out (off): the change appends it */
    static const test_change ON = {GP_UF_PROFILE_THRUST, PROFILE_S2_LINE, 45, -1};
    hold_plan_3(&auth);
    expected_len = signed_variant("profile 0 1 0.4 200 0.3", "profile 0 1 0.4 200 0.3 4.5", 4,
                                  expected);
    size_t len = make_update(3, 4, held, held_len, expected, expected_len, &ON, 1, KEY, u);
    CHECK_INT(gp_update_apply(u, len, held, held_len, &auth, hybrid, out, &new_len, &plan,
                              message), GP_UPDATE_APPLIED);
    CHECK(new_len == expected_len && memcmp(out, expected, expected_len) == 0);
    CHECK_NEAR(plan.states[1].profiles[0].thrust_w, 4.5, 0);

    /* from the plan it makes, a change of the field now on the line, and its speed */
    memcpy(held, out, new_len);
    held_len = new_len;
    auth.last_seq = 4;
    memcpy(auth.last_tag, plan.tag, sizeof plan.tag);
    static const test_change MORE[] = {{GP_UF_PROFILE_SPEED, PROFILE_S2_LINE, 42, -2},
                                       {GP_UF_PROFILE_THRUST, PROFILE_S2_LINE, 9, 0}};
    expected_len = signed_variant("profile 0 1 0.4 200 0.3", "profile 0 1 0.4 200 0.42 9", 5,
                                  expected);
    len = make_update(4, 5, held, held_len, expected, expected_len, MORE, 2, KEY, u);
    CHECK_INT(gp_update_apply(u, len, held, held_len, &auth, hybrid, out, &new_len, &plan,
                              message), GP_UPDATE_APPLIED);
    CHECK(new_len == expected_len && memcmp(out, expected, expected_len) == 0);
    CHECK_NEAR(plan.states[1].profiles[0].thrust_w, 9, 0);
    CHECK_NEAR(plan.states[1].profiles[0].speed_mps, 0.42, 0);

    /* beyond the thruster's rating: refused, the plan in force stays */
    static const test_change OVER = {GP_UF_PROFILE_THRUST, PROFILE_S2_LINE, 12, 0};
    expected_len = signed_variant("profile 0 1 0.4 200 0.3", "profile 0 1 0.4 200 0.42 12", 6,
                                  expected);
    auth.last_seq = 5;
    memcpy(auth.last_tag, plan.tag, sizeof plan.tag);
    memcpy(held, out, new_len);
    held_len = new_len;
    len = make_update(5, 6, held, held_len, expected, expected_len, &OVER, 1, KEY, u);
    CHECK_INT(gp_update_apply(u, len, held, held_len, &auth, hybrid, out, &new_len, &plan,
                              message), GP_UPDATE_BAD_PLAN);
    CHECK_CONTAINS(message, "THRUST_W 12 outside the vehicle's thruster (1-9 W)");
    CHECK_INT(plan.seq, 5);
    /* on a glider without a thruster any thrust is refused */
    hold_plan_3(&auth);
    expected_len = signed_variant("profile 0 1 0.4 200 0.3", "profile 0 1 0.4 200 0.3 4.5", 4,
                                  expected);
    len = make_update(3, 4, held, held_len, expected, expected_len, &ON, 1, KEY, u);
    CHECK_INT(apply(u, len, &auth, message, &new_len), GP_UPDATE_BAD_PLAN);
    CHECK_CONTAINS(message, "THRUST_W 4.5 on a vehicle without a thruster");
}

void test_update_decimal_text_should_write_plan_numbers(void)
{
    static const struct {
        int64_t mantissa;
        int exponent;
        const char *text;
    } CASES[] = {
        {0, 0, "0"}, {3, 2, "300"}, {425, -1, "42.5"}, {25, -8, "0.00000025"},
        {-25, -8, "-0.00000025"}, {1891, -1, "189.1"}, {5, -1, "0.5"}, {-7, 0, "-7"},
        {999999999999999LL, 20, "99999999999999900000000000000000000"},
        {1, -20, "0.00000000000000000001"},
    };
    for (size_t i = 0; i < sizeof CASES / sizeof CASES[0]; i++) {
        char text[48];
        size_t n = gp_update_decimal_text(CASES[i].mantissa, CASES[i].exponent, text);
        CHECK_INT(n, strlen(CASES[i].text));
        CHECK_CONTAINS(text, CASES[i].text);
    }
}

void test_random_updates_should_never_crash_the_applier(void)
{
    gp_plan_auth auth;
    uint8_t u[GP_MAX_UPDATE_BYTES];
    char message[GP_UPDATE_MESSAGE_LEN];
    size_t new_len = 0;
    unsigned state = 12345;
    hold_plan_3(&auth);
    for (int round = 0; round < 3000; round++) {
        size_t n = gp_test_random(&state) % (GP_MAX_UPDATE_BYTES - 60);
        uint8_t changes[GP_MAX_UPDATE_BYTES];
        for (size_t i = 0; i < n; i++) {  /* small codes, lines and exponents, often */
            unsigned r = gp_test_random(&state);
            changes[i] = (uint8_t)(r % 4 == 0 ? r >> 8 : (r >> 8) % 24);
        }
        size_t len = raw_update(changes, n, (int)(gp_test_random(&state) % 8), u);
        gp_update_status status = apply(u, len, &auth, message, &new_len);
        CHECK(status <= GP_UPDATE_NOT_STORED && message[0] != '\0');
        CHECK(status != GP_UPDATE_APPLIED || plan.seq == 4);
        if (status == GP_UPDATE_APPLIED) {
            hold_plan_3(&auth);
        }
    }
}
