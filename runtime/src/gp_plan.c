/* Strict reader of the plan file (docs/plan-format.md) and the schedule it sets.
 * One pass over the bytes, then one line at a time with a fixed field array; the
 * first rule broken rejects the whole file and names its line. */
#include "gp_plan.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gp_crc.h"
#include "gp_sha256.h"

#define MAX_FIELDS (GP_MAX_PLAN_COMPONENTS + 1) /* the `components` and `energy` lines */
#define MAX_VISITS 999999999                    /* a COUNT has at most 9 digits */
#define SHARE_TOLERANCE 1e-6
#define HALF_PI 1.57079632679489661923
/* printf arguments for "%.*s" of a field, at most a name's length of it */
#define SHOWN(f) (int)((f)->len > GP_MAX_NAME_LENGTH ? GP_MAX_NAME_LENGTH : (f)->len), (f)->start

typedef struct {
    const char *start;
    size_t len;
} field;

typedef struct {
    const char *text;
    size_t len, pos;      /* pos: start of the next line */
    int line_no;          /* number of the line in `fields` */
    field fields[MAX_FIELDS];
    int n_fields;
    char *error;
} reader;

static int fail(reader *r, const char *format, ...)
{
    int n = snprintf(r->error, GP_PLAN_ERROR_LEN, "line %d: ", r->line_no);
    va_list args;
    va_start(args, format);
    vsnprintf(r->error + n, (size_t)(GP_PLAN_ERROR_LEN - n), format, args);
    va_end(args);
    return -1;
}

/* Split the next line into fields; the byte rules were checked before. With
 * `text_from` > 0, the words from that field on are one TEXT field (`assume`). */
static int next_line(reader *r, int text_from)
{
    r->line_no++;
    const char *line = r->text + r->pos;
    const char *end = r->pos < r->len ? memchr(line, '\n', r->len - r->pos) : NULL;
    if (end == NULL) {
        return fail(r, "the plan ends before this line (truncated file)");
    }
    size_t line_len = (size_t)(end - line);
    r->pos += line_len + 1;
    r->n_fields = 0;
    if (line_len == 0) {
        return fail(r, "empty line");
    }
    size_t i = 0;
    while (i <= line_len) {
        size_t j = i;
        while (j < line_len && line[j] != ' ') {
            j++;
        }
        if (j == i) {
            return fail(r, "fields must be separated by exactly one space, without "
                           "leading or trailing spaces");
        }
        if (text_from > 0 && r->n_fields == text_from + 1) {
            field *text = &r->fields[text_from];  /* one more word of the TEXT */
            text->len = (size_t)(line + j - text->start);
        } else if (r->n_fields == MAX_FIELDS) {
            return fail(r, "too many fields");
        } else {
            r->fields[r->n_fields++] = (field){line + i, j - i};
        }
        i = j + 1;
    }
    return 0;
}

static int field_is(const field *f, const char *word)
{
    return f->len == strlen(word) && memcmp(f->start, word, f->len) == 0;
}

/* Next line must be `keyword` with min_fields..max_fields fields in all (the keyword
 * counted); `text_from` as for next_line. */
static int expect_fields(reader *r, const char *keyword, int min_fields, int max_fields,
                         int text_from)
{
    if (r->pos >= r->len) {
        r->line_no++;
        return fail(r, "missing '%s' line (truncated file)", keyword);
    }
    if (next_line(r, text_from) < 0) {
        return -1;
    }
    if (!field_is(&r->fields[0], keyword)) {
        return fail(r, "expected a '%s' line, found '%.*s'", keyword, SHOWN(&r->fields[0]));
    }
    if (r->n_fields < min_fields || r->n_fields > max_fields) {
        if (min_fields == max_fields) {
            return fail(r, "'%s' takes %d fields, found %d", keyword, min_fields - 1,
                        r->n_fields - 1);
        }
        return fail(r, "'%s' takes %d to %d fields, found %d", keyword, min_fields - 1,
                    max_fields - 1, r->n_fields - 1);
    }
    return 0;
}

/* Next line must be `keyword` with n_fields fields in all. */
static int expect(reader *r, const char *keyword, int n_fields)
{
    return expect_fields(r, keyword, n_fields, n_fields, 0);
}

static int is_name(const field *f)
{
    if (f->len < 1 || f->len > GP_MAX_NAME_LENGTH) {
        return 0;
    }
    for (size_t i = 0; i < f->len; i++) {
        char c = f->start[i];
        int alpha = (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || c == '_';
        if (!alpha && !(i > 0 && c >= '0' && c <= '9')) {
            return 0;
        }
    }
    return 1;
}

static int name_field(reader *r, int index, const char *what)
{
    if (!is_name(&r->fields[index])) {
        return fail(r, "%s is not a NAME", what);
    }
    return 0;
}

static size_t digits(const char *s, size_t i, size_t len)
{
    size_t j = i;
    while (j < len && s[j] >= '0' && s[j] <= '9') {
        j++;
    }
    return j - i;
}

/* NUMBER: -?[0-9]+(\.[0-9]+)?([eE][-+]?[0-9]+)?, finite. */
static int number_field(reader *r, int index, const char *what, double *out)
{
    const field *f = &r->fields[index];
    const char *s = f->start;
    size_t i = (f->len > 0 && s[0] == '-') ? 1 : 0, n;
    int ok = (n = digits(s, i, f->len)) > 0;
    i += n;
    if (ok && i < f->len && s[i] == '.') {
        ok = (n = digits(s, i + 1, f->len)) > 0;
        i += 1 + n;
    }
    if (ok && i < f->len && (s[i] == 'e' || s[i] == 'E')) {
        i++;
        if (i < f->len && (s[i] == '+' || s[i] == '-')) {
            i++;
        }
        ok = (n = digits(s, i, f->len)) > 0;
        i += n;
    }
    if (!ok || i != f->len) {
        return fail(r, "%s '%.*s' is not a NUMBER", what, SHOWN(f));
    }
    char buf[GP_MAX_PLAN_LINE_BYTES + 1];
    memcpy(buf, s, f->len);
    buf[f->len] = '\0';
    *out = strtod(buf, NULL);
    if (!isfinite(*out)) {
        return fail(r, "%s %s is not finite", what, buf);
    }
    return 0;
}

static int count_field(reader *r, int index, const char *what, int low, int high, int *out)
{
    const field *f = &r->fields[index];
    if (f->len == 0 || f->len > 9 || digits(f->start, 0, f->len) != f->len) {
        return fail(r, "%s '%.*s' is not a COUNT", what, SHOWN(f));
    }
    int value = 0;
    for (size_t i = 0; i < f->len; i++) {
        value = value * 10 + (f->start[i] - '0');
    }
    if (value < low || value > high) {
        return fail(r, "%s %d outside %d..%d", what, value, low, high);
    }
    *out = value;
    return 0;
}

static int hex_field(reader *r, int index, size_t n_digits, const char *what)
{
    const field *f = &r->fields[index];
    int ok = f->len == n_digits;
    for (size_t i = 0; ok && i < f->len; i++) {
        char c = f->start[i];
        ok = (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f');
    }
    if (!ok) {
        return fail(r, "%s needs %zu lowercase hex digits", what, n_digits);
    }
    return 0;
}

static int matches(const field *f, const char *name)
{
    return name != NULL && field_is(f, name);
}

/* ---- the file ---------------------------------------------------------------- */

/* The value of `n` lowercase hex digits (already checked) into bytes or a u32. */
static uint8_t hex_digit(char c)
{
    return (uint8_t)(c <= '9' ? c - '0' : c - 'a' + 10);
}

/* `line` (without its LF) is `keyword ` and a field; the field into r->fields[0]. */
static int tail_line(reader *r, const char *line, size_t len, const char *keyword)
{
    size_t k = strlen(keyword);
    if (len <= k + 1 || memcmp(line, keyword, k) != 0 || line[k] != ' ') {
        return 0;
    }
    r->fields[0] = (field){line + k + 1, len - k - 1};
    return 1;
}

/* `seq COUNT` of a signed plan: 1..GP_MAX_PLAN_SEQUENCE, no leading zero. */
static int sequence_field(reader *r, uint32_t *out)
{
    const field *f = &r->fields[0];
    uint64_t value = 0;
    if (f->len > 10 || digits(f->start, 0, f->len) != f->len || f->start[0] == '0') {
        return fail(r, "seq '%.*s' is not a COUNT from 1", SHOWN(f));
    }
    for (size_t i = 0; i < f->len; i++) {
        value = value * 10 + (uint64_t)(f->start[i] - '0');
    }
    if (value > GP_MAX_PLAN_SEQUENCE) {
        return fail(r, "seq %.*s exceeds %lu", SHOWN(f), (unsigned long)GP_MAX_PLAN_SEQUENCE);
    }
    *out = (uint32_t)value;
    return 0;
}

/* Where the lines at the end of a file lie: [start, end) without the LF. */
typedef struct {
    size_t start, end;
} span;

/* A signed plan ends in `seq COUNT` and `hmac HEX64` after its crc32 line: the HMAC-SHA256
 * of every byte before the hmac line under the vehicle's key. Checked before anything
 * else is read, so that nobody without the key gets the reader to look at their bytes.
 * `tail`: the last three lines, the last at tail[2]; `n_lines` in the file. On success
 * `crc` is the span of the crc32 line and r->line_no its number. */
static int check_signature(reader *r, const span tail[3], int n_lines,
                           const gp_plan_auth *auth, gp_plan *plan, span *crc)
{
    const char *hmac_line = r->text + tail[2].start;
    r->line_no = n_lines;
    *crc = tail[2];
    if (!tail_line(r, hmac_line, tail[2].end - tail[2].start, "hmac")) {
        if (auth != NULL) {
            return fail(r, "the plan is not signed, and this runtime holds a key: it flies "
                           "signed plans only (gliderplan plan --sign KEYFILE)");
        }
        return 0;
    }
    if (hex_field(r, 0, 2 * GP_SHA256_SIZE, "hmac") < 0) {
        return -1;
    }
    for (int i = 0; i < GP_SHA256_SIZE; i++) {
        plan->tag[i] = (uint8_t)(hex_digit(hmac_line[5 + 2 * i]) << 4
                                 | hex_digit(hmac_line[6 + 2 * i]));
    }
    r->line_no = n_lines - 1;
    if (n_lines < 3 || !tail_line(r, r->text + tail[1].start, tail[1].end - tail[1].start, "seq")) {
        return fail(r, "a signed plan needs 'seq COUNT' before its 'hmac' line");
    }
    if (sequence_field(r, &plan->seq) < 0) {
        return -1;
    }
    if (auth != NULL) {
        gp_hmac_sha256 mac;
        uint8_t tag[GP_SHA256_SIZE];
        gp_hmac_sha256_init(&mac, auth->key, GP_PLAN_KEY_BYTES);
        gp_hmac_sha256_update(&mac, r->text, tail[2].start);
        gp_hmac_sha256_final(&mac, tag);
        if (!gp_tags_equal(tag, plan->tag)) {
            r->line_no = n_lines;
            return fail(r, "the signature does not match: the plan was changed after it was "
                           "signed, or signed with another key");
        }
        if (plan->seq < auth->last_seq) {
            return fail(r, "seq %lu is older than the plan in force (seq %lu): a replayed "
                           "plan", (unsigned long)plan->seq, (unsigned long)auth->last_seq);
        }
        if (plan->seq == auth->last_seq && !gp_tags_equal(tag, auth->last_tag)) {
            return fail(r, "seq %lu is the plan in force's, but this is another plan: each "
                           "plan needs a new seq", (unsigned long)plan->seq);
        }
    }
    plan->is_signed = 1;
    r->line_no = n_lines - 2;
    *crc = tail[0];
    return 0;
}

/* Bytes, line lengths, final LF, the signature, the final crc32 line and the checksum. */
static int check_bytes(reader *r, const gp_plan_auth *auth, gp_plan *plan,
                       size_t *crc_line_start)
{
    r->line_no = 1;
    if (r->len == 0) {
        return fail(r, "empty file (truncated)");
    }
    if (r->len > GP_MAX_PLAN_BYTES) {
        return fail(r, "file of %zu bytes exceeds %d", r->len, GP_MAX_PLAN_BYTES);
    }
    size_t line_start = 0;
    span tail[3] = {{0, 0}, {0, 0}, {0, 0}};  /* the last three lines */
    int n_lines = 0;
    for (size_t i = 0; i < r->len; i++) {
        unsigned char c = (unsigned char)r->text[i];
        if (c != '\n' && (c < 0x20 || c > 0x7E)) {
            return fail(r, "byte 0x%02x is not allowed (printable ASCII and LF only)", c);
        }
        if (i - line_start + 1 > GP_MAX_PLAN_LINE_BYTES) {
            return fail(r, "longer than %d bytes", GP_MAX_PLAN_LINE_BYTES);
        }
        if (c == '\n') {
            tail[0] = tail[1];
            tail[1] = tail[2];
            tail[2] = (span){line_start, i};
            line_start = i + 1;
            n_lines++;
            if (i + 1 < r->len) {
                r->line_no++;
            }
        }
    }
    if (r->text[r->len - 1] != '\n') {
        return fail(r, "no final LF (truncated file)");
    }
    span crc;
    if (check_signature(r, tail, n_lines, auth, plan, &crc) < 0) {
        return -1;
    }
    const char *last = r->text + crc.start;
    if ((plan->is_signed && n_lines < 3) || crc.end - crc.start != 6 + 8
        || memcmp(last, "crc32 ", 6) != 0) {
        return fail(r, "the last line is not 'crc32 HEX8' (truncated file)");
    }
    r->fields[0] = (field){last + 6, 8};
    if (hex_field(r, 0, 8, "crc32") < 0) {
        return -1;
    }
    uint32_t stated = 0;
    for (int i = 6; i < 14; i++) {
        stated = stated << 4 | hex_digit(last[i]);
    }
    uint32_t computed = gp_crc32(0, (const uint8_t *)r->text, crc.start);
    if (stated != computed) {
        return fail(r, "checksum mismatch: the file says %08x, its bytes give %08x", stated,
                    (unsigned)computed);
    }
    *crc_line_start = crc.start;
    return 0;
}

/* A NUMBER in [0, most] in field `index`. */
static int amount_field(reader *r, int index, const char *what, double most, double *out)
{
    if (number_field(r, index, what, out) < 0) {
        return -1;
    }
    if (!(*out >= 0)) {
        return fail(r, "%s must be >= 0", what);
    }
    if (*out > most) {
        return fail(r, "%s %g exceeds %g", what, *out, most);
    }
    return 0;
}

/* The mission was compiled for no board (`computer none`): its one clock is 0. */
static int built_for_no_board(const gp_mission *mission)
{
    return mission->n_clocks == 1 && mission->clocks_mhz[0] == 0;
}

/* Whether a plan for board `computer` is for another board than the mission's: its clocks
 * are not checked against the mission's board, gp_plan_check refuses the board. */
static int for_another_board(const gp_mission *mission, const char *computer)
{
    const gp_plan_bounds *bounds = mission->bounds;
    return bounds != NULL && bounds->board != NULL && strcmp(computer, bounds->board) != 0;
}

/* A clock [MHz] in field `index`: in a plan for `computer none` (`no_board`) 0, there
 * being no clock to set, whatever board the mission was compiled for; else above 0 and,
 * unless the plan is for another board (`other_board`), one of the clocks of the board
 * the mission flies on. */
static int clock_field(reader *r, int index, const gp_mission *mission, int no_board,
                       int other_board, double *out)
{
    if (number_field(r, index, "CLOCK_MHZ", out) < 0) {
        return -1;
    }
    if (no_board) {
        return *out == 0 ? 0 : fail(r, "clock %g MHz: computer " GP_NO_BOARD " has no clock "
                                       "to set, its clocks are 0", *out);
    }
    if (other_board) {
        return *out > 0 ? 0 : fail(r, "the clock must be > 0 MHz");
    }
    if (built_for_no_board(mission)) {
        return fail(r, "clock %g MHz: the mission names no board (computer " GP_NO_BOARD
                       "): a plan for it says 'computer " GP_NO_BOARD " 0'", *out);
    }
    for (int i = 0; i < mission->n_clocks; i++) {
        if (fabs(*out - mission->clocks_mhz[i]) <= GP_CLOCK_TOLERANCE_MHZ) {
            return 0;
        }
    }
    char clocks[64];
    int n = 0;
    for (int i = 0; i < mission->n_clocks && n < (int)sizeof clocks - 16; i++) {
        n += snprintf(clocks + n, sizeof clocks - (size_t)n, "%s%g", i ? ", " : "",
                      mission->clocks_mhz[i]);
    }
    return fail(r, "clock %g MHz: the board has %s MHz", *out, clocks);
}

/* `components NAME...`: the energy columns of every state's `energy` line, distinct. */
static int read_components(reader *r, gp_plan *plan)
{
    if (expect_fields(r, "components", 2, GP_MAX_PLAN_COMPONENTS + 1, 0) < 0) {
        return -1;
    }
    for (int i = 1; i < r->n_fields; i++) {
        if (name_field(r, i, "component") < 0) {
            return -1;
        }
        for (int k = 1; k < i; k++) {
            if (r->fields[k].len == r->fields[i].len
                && memcmp(r->fields[k].start, r->fields[i].start, r->fields[i].len) == 0) {
                return fail(r, "component '%.*s' named twice", SHOWN(&r->fields[i]));
            }
        }
    }
    plan->n_components = (uint8_t)(r->n_fields - 1);
    return 0;
}

/* `assumptions COUNT` and COUNT lines `assume SUBJECT TEXT`: what the prediction rests
 * on, for people; the runtime only checks their form. */
static int read_assumptions(reader *r, gp_plan *plan)
{
    int count;
    if (expect(r, "assumptions", 2) < 0
        || count_field(r, 1, "assumptions", 0, GP_MAX_PLAN_ASSUMPTIONS, &count) < 0) {
        return -1;
    }
    for (int i = 0; i < count; i++) {
        if (expect_fields(r, "assume", 3, 3, 2) < 0 || name_field(r, 1, "SUBJECT") < 0) {
            return -1;
        }
    }
    plan->n_assumptions = (uint8_t)count;
    return 0;
}

static int read_header(reader *r, const gp_mission *mission, gp_plan *plan)
{
    int count;
    char version[12];
    snprintf(version, sizeof version, "%d", GP_PLAN_FORMAT_VERSION);
    if (next_line(r, 0) < 0) {
        return -1;
    }
    if (r->n_fields != 2 || !field_is(&r->fields[0], "GPPLAN")) {
        return fail(r, "expected 'GPPLAN %s': not a plan file", version);
    }
    if (!field_is(&r->fields[1], version)) {
        return fail(r, "plan format version '%.*s', this runtime reads version %s",
                    SHOWN(&r->fields[1]), version);
    }
    if (expect(r, "mission", 2) < 0 || name_field(r, 1, "mission name") < 0) {
        return -1;
    }
    if (!matches(&r->fields[1], mission->name)) {
        return fail(r, "plan is for mission '%.*s', this runtime runs '%.32s'",
                    SHOWN(&r->fields[1]), mission->name);
    }
    if (expect(r, "hash", 2) < 0 || hex_field(r, 1, 64, "hash") < 0) {
        return -1;
    }
    if (!matches(&r->fields[1], mission->hash)) {
        return fail(r, "hash does not match the compiled mission (plan made for another "
                       "version of '%.32s')", mission->name);
    }
    if (expect(r, "computer", 3) < 0 || name_field(r, 1, "computer") < 0) {
        return -1;
    }
    memcpy(plan->computer, r->fields[1].start, r->fields[1].len);
    plan->computer[r->fields[1].len] = '\0';
    if (clock_field(r, 2, mission, strcmp(plan->computer, GP_NO_BOARD) == 0,
                    for_another_board(mission, plan->computer), &plan->clock_mhz) < 0) {
        return -1;
    }
    if (expect(r, "budget_j", 2) < 0
        || amount_field(r, 1, "budget_j", GP_MAX_PLAN_ENERGY_J, &plan->budget_j) < 0
        || expect(r, "predicted_j", 2) < 0
        || amount_field(r, 1, "predicted_j", GP_MAX_PLAN_ENERGY_J, &plan->predicted_j) < 0) {
        return -1;
    }
    if (read_components(r, plan) < 0 || read_assumptions(r, plan) < 0) {
        return -1;
    }
    if (expect(r, "states", 2) < 0 || count_field(r, 1, "states", 1, GP_MAX_STATES, &count) < 0) {
        return -1;
    }
    if (count != mission->n_states) {
        return fail(r, "plan has %d states, mission '%.32s' has %d", count, mission->name,
                    mission->n_states);
    }
    plan->n_states = (uint8_t)count;
    return 0;
}

static int sensor_index(const gp_mission *mission, const field *f)
{
    for (int i = 0; i < GP_N_SENSORS; i++) {
        if (mission->sensor_names && matches(f, mission->sensor_names[i])) {
            return i;
        }
    }
    return -1;
}

static int read_sensor(reader *r, const gp_mission *mission, const gp_state *state,
                       int *logged_from, gp_plan_sensor *out)
{
    if (expect(r, "sensor", 4) < 0 || name_field(r, 1, "sensor") < 0) {
        return -1;
    }
    int index = sensor_index(mission, &r->fields[1]);
    int position = -1;
    for (int i = *logged_from; index >= 0 && i < state->n_sensors; i++) {
        if (state->sensors[i] == index) {
            position = i;
            break;
        }
    }
    if (position < 0) {
        return fail(r, "sensor '%.*s' is not logged by state '%.32s' (or out of order)",
                    SHOWN(&r->fields[1]), state->name);
    }
    *logged_from = position + 1;
    out->sensor = (uint8_t)index;
    if (number_field(r, 2, "PERIOD_S", &out->period_s) < 0
        || number_field(r, 3, "ON_S", &out->on_s) < 0) {
        return -1;
    }
    if (!(out->period_s > 0) || out->on_s < 0 || out->on_s > out->period_s) {
        return fail(r, "need PERIOD_S > 0 and 0 <= ON_S <= PERIOD_S");
    }
    if (out->period_s > GP_MAX_PLAN_TIME_S) {
        return fail(r, "PERIOD_S %g exceeds %g", out->period_s, GP_MAX_PLAN_TIME_S);
    }
    return 0;
}

static int read_profile(reader *r, int expected_index, gp_plan_profile *out)
{
    int index;
    /* `profile INDEX SHARE PITCH_RAD BALLAST_CC SPEED_MPS [THRUST_W]` */
    if (expect_fields(r, "profile", 6, 7, 0) < 0
        || count_field(r, 1, "profile INDEX", 0, GP_MAX_PROFILE_ALTERNATIVES - 1, &index) < 0) {
        return -1;
    }
    if (index != expected_index) {
        return fail(r, "profile INDEX %d out of order, expected %d", index, expected_index);
    }
    if (number_field(r, 2, "SHARE", &out->share) < 0
        || number_field(r, 3, "PITCH_RAD", &out->pitch_rad) < 0
        || number_field(r, 4, "BALLAST_CC", &out->ballast_cc) < 0
        || number_field(r, 5, "SPEED_MPS", &out->speed_mps) < 0) {
        return -1;
    }
    out->thrust_w = 0.0;  /* left out: the thruster is off */
    if (r->n_fields == 7 && number_field(r, 6, "THRUST_W", &out->thrust_w) < 0) {
        return -1;
    }
    if (!(out->thrust_w >= 0 && out->thrust_w <= GP_MAX_PLAN_THRUST_W)) {
        return fail(r, "THRUST_W %g outside [0, %g]", out->thrust_w, GP_MAX_PLAN_THRUST_W);
    }
    if (out->share < 0 || out->share > 1) {
        return fail(r, "SHARE %g outside [0, 1]", out->share);
    }
    /* pitch and ballast 0: a propelled profile, flown level on its propeller */
    int level = out->pitch_rad == 0.0 && out->ballast_cc == 0.0;
    if (!level && !(out->pitch_rad > 0 && out->pitch_rad < HALF_PI)) {
        return fail(r, "PITCH_RAD %g outside (0, pi/2)", out->pitch_rad);
    }
    if (!(level || out->ballast_cc > 0) || !(out->speed_mps > 0)) {
        return fail(r, "BALLAST_CC and SPEED_MPS must be > 0");
    }
    if (out->speed_mps > GP_MAX_PLAN_SPEED_MPS) {
        return fail(r, "SPEED_MPS %g exceeds %g", out->speed_mps, GP_MAX_PLAN_SPEED_MPS);
    }
    return 0;
}

/* `predict TIME_S VISITS INFLECTIONS` and `energy J...`: what the plan predicts of the
 * state; the simulator checks a flight against it, the runtime its form and that its sum
 * is the plan's `predicted_j` (into `energy_j`). */
static int read_prediction(reader *r, int n_components, double *energy_j)
{
    double amount;
    int visits;
    if (expect(r, "predict", 4) < 0
        || amount_field(r, 1, "TIME_S", GP_MAX_PLAN_TIME_S, &amount) < 0
        || count_field(r, 2, "VISITS", 0, MAX_VISITS, &visits) < 0
        || amount_field(r, 3, "INFLECTIONS", GP_MAX_PLAN_INFLECTIONS, &amount) < 0) {
        return -1;
    }
    if (expect(r, "energy", n_components + 1) < 0) {
        return -1;
    }
    for (int i = 1; i <= n_components; i++) {
        if (amount_field(r, i, "energy", GP_MAX_PLAN_ENERGY_J, &amount) < 0) {
            return -1;
        }
        *energy_j += amount;
    }
    return 0;
}

/* Whether the next line is a `keyword` line (for an optional line). */
static int coming(const reader *r, const char *keyword)
{
    size_t n = strlen(keyword);
    return r->pos + n < r->len && memcmp(r->text + r->pos, keyword, n) == 0
        && r->text[r->pos + n] == ' ';
}

/* `power SLEEP CYCLES_PER_TICK`, optional (absent: awake between ticks, the runtime's own
 * work): SLEEP 1 only where the mission's state sleeps between ticks. */
static int read_power(reader *r, const gp_state *state, gp_plan_state *out)
{
    int sleep = 0;
    out->sleep = 0;
    out->cycles_per_tick = 0;
    if (!coming(r, "power")) {
        return 0;
    }
    if (expect(r, "power", 3) < 0 || count_field(r, 1, "SLEEP", 0, 1, &sleep) < 0
        || number_field(r, 2, "CYCLES_PER_TICK", &out->cycles_per_tick) < 0) {
        return -1;
    }
    if (!(out->cycles_per_tick > 0)) {
        return fail(r, "CYCLES_PER_TICK must be > 0");
    }
    if (sleep && !state->sleep) {
        return fail(r, "SLEEP 1 where state '%.32s' does not sleep between ticks", state->name);
    }
    out->sleep = (uint8_t)sleep;
    return 0;
}

/* State block `s`; `no_board`: the plan is for `computer none`, `other_board`: for a
 * board not the mission's. */
static int read_state(reader *r, const gp_mission *mission, int n_components, int s,
                      int no_board, int other_board, gp_plan_state *out)
{
    const gp_state *state = &mission->states[s];
    int n_sensors, n_profiles, logged_from = 0;
    if (expect(r, "state", 6) < 0 || name_field(r, 1, "state name") < 0) {
        return -1;
    }
    if (!matches(&r->fields[1], state->name)) {
        return fail(r, "state '%.*s' where the mission has '%.32s'", (int)r->fields[1].len,
                    r->fields[1].start, state->name);
    }
    out->line = r->line_no;
    if (clock_field(r, 2, mission, no_board, other_board, &out->clock_mhz) < 0
        || number_field(r, 3, "CYCLE_S", &out->cycle_s) < 0
        || count_field(r, 4, "N_SENSORS", 0, GP_MAX_PLAN_SENSORS, &n_sensors) < 0
        || count_field(r, 5, "N_PROFILES", 1, GP_MAX_PROFILE_ALTERNATIVES, &n_profiles) < 0) {
        return -1;
    }
    if (!(out->cycle_s > 0) || out->cycle_s > GP_MAX_PLAN_TIME_S) {
        return fail(r, "CYCLE_S must lie in (0, %g]", GP_MAX_PLAN_TIME_S);
    }
    if (n_profiles != state->n_profiles) {
        return fail(r, "%d profiles, state '%.32s' has %d", n_profiles, state->name,
                    state->n_profiles);
    }
    if (read_power(r, state, out) < 0 || read_prediction(r, n_components, &out->energy_j) < 0) {
        return -1;
    }
    out->n_sensors = (uint8_t)n_sensors;
    out->n_profiles = (uint8_t)n_profiles;
    for (int i = 0; i < n_sensors; i++) {
        if (read_sensor(r, mission, state, &logged_from, &out->sensors[i]) < 0) {
            return -1;
        }
    }
    double total = 0;
    for (int i = 0; i < n_profiles; i++) {
        if (read_profile(r, i, &out->profiles[i]) < 0) {
            return -1;
        }
        total += out->profiles[i].share;
    }
    if (expect(r, "end", 1) < 0) {
        return -1;
    }
    if (fabs(total - 1.0) > SHARE_TOLERANCE) {
        return fail(r, "shares of state '%.32s' sum to %.9g, not 1", state->name, total);
    }
    return 0;
}

int gp_plan_read(const char *text, size_t len, const gp_mission *mission,
                 const gp_plan_auth *auth, gp_plan *out, char error[GP_PLAN_ERROR_LEN])
{
    /* Static: a plan is ~40 KiB, too big for a small board's stack. Not reentrant. */
    static gp_plan plan;
    reader r = {.text = text, .len = len, .error = error};
    size_t crc_line_start = 0;
    error[0] = '\0';
    memset(&plan, 0, sizeof plan);
    if (check_bytes(&r, auth, &plan, &crc_line_start) < 0) {
        return -1;
    }
    r.line_no = 0;
    r.len = crc_line_start;  /* the crc32 line was checked: read up to it */
    if (read_header(&r, mission, &plan) < 0) {
        return -1;
    }
    int no_board = strcmp(plan.computer, GP_NO_BOARD) == 0;
    int other_board = for_another_board(mission, plan.computer);
    for (int s = 0; s < plan.n_states; s++) {
        if (read_state(&r, mission, plan.n_components, s, no_board, other_board,
                       &plan.states[s]) < 0) {
            return -1;
        }
    }
    if (r.pos < r.len) {
        next_line(&r, 0);
        return fail(&r, "extra line after the last state block");
    }
    if (gp_plan_check(&plan, mission, error) < 0) {
        return -1;
    }
    *out = plan;
    return 0;
}

/* ---- the plan against its mission (contract/plan_check.py) ----------------------- */

/* Lines of the plan file's header: fixed by the format. */
enum { COMPUTER_LINE = 4, BUDGET_LINE = 5, PREDICTED_LINE = 6 };

/* A mission table without bounds holds a plan to the contract's. */
static const gp_plan_bounds contract_bounds = {
    .board = NULL, .max_budget_j = GP_MAX_PLAN_ENERGY_J, .min_pitch_rad = 0,
    .max_pitch_rad = HALF_PI, .max_speed_mps = GP_MAX_PLAN_SPEED_MPS,
    .min_propelled_mps = 0, .max_propelled_mps = GP_MAX_PLAN_SPEED_MPS,
    .min_thrust_w = 0, .max_thrust_w = GP_MAX_PLAN_THRUST_W, .states = NULL,
};

static int refuse(char error[GP_PLAN_ERROR_LEN], int line, const char *format, ...)
{
    int n = snprintf(error, GP_PLAN_ERROR_LEN, "line %d: ", line);
    va_list args;
    va_start(args, format);
    vsnprintf(error + n, (size_t)(GP_PLAN_ERROR_LEN - n), format, args);
    va_end(args);
    return -1;
}

/* `value` exceeds `bound` by more than the plan file's rounding. */
static int above(double value, double bound)
{
    return value > bound + GP_PLAN_ROUNDING * fabs(bound);
}

/* The duty [1] a state's plan gives `sensor`: a sensor without a line is always on. */
static double planned_duty(const gp_plan_state *ps, uint8_t sensor)
{
    for (int i = 0; i < ps->n_sensors; i++) {
        if (ps->sensors[i].sensor == sensor) {
            return ps->sensors[i].on_s / ps->sensors[i].period_s;
        }
    }
    return 1.0;
}

static int check_state(const gp_plan_state *ps, const gp_state *state,
                       const gp_state_bounds *sb, const gp_mission *mission,
                       const gp_plan_bounds *b, char error[GP_PLAN_ERROR_LEN])
{
    for (int i = 0; sb != NULL && i < sb->n_duties; i++) {
        const gp_duty_bound *d = &sb->duties[i];
        double flown = planned_duty(ps, d->sensor);
        if (flown < d->low - GP_PLAN_ROUNDING || above(flown, d->high)) {
            return refuse(error, ps->line, "state %.32s: sensor %.32s: duty %g outside the "
                          "mission's [%g, %g]", state->name, mission->sensor_names[d->sensor],
                          flown, d->low, d->high);
        }
    }
    for (int k = 0; k < ps->n_profiles; k++) {
        const gp_plan_profile *p = &ps->profiles[k];
        double least = sb != NULL ? sb->min_ballast_cc[k] : 0;
        if (p->pitch_rad == 0.0 && p->ballast_cc == 0.0) {  /* level: propelled */
            if (!(mission->unplanned_speed_mps > 0)) {
                return refuse(error, ps->line, "state %.32s: profile %d: PITCH_RAD and "
                              "BALLAST_CC 0 fly it level on a propeller, and the vehicle has "
                              "none", state->name, k);
            }
            if (above(b->min_propelled_mps, p->speed_mps)
                || above(p->speed_mps, b->max_propelled_mps)) {
                return refuse(error, ps->line, "state %.32s: profile %d: SPEED_MPS %g outside "
                              "the vehicle's propulsion (%g-%g m/s)", state->name, k,
                              p->speed_mps, b->min_propelled_mps, b->max_propelled_mps);
            }
            continue;  /* no glide */
        }
        if (p->thrust_w > 0 && !(mission->unplanned_speed_mps > 0)) {
            return refuse(error, ps->line, "state %.32s: profile %d: THRUST_W %g on a vehicle "
                          "without a thruster", state->name, k, p->thrust_w);
        }
        if (p->thrust_w > 0 && (above(b->min_thrust_w, p->thrust_w)
                                || above(p->thrust_w, b->max_thrust_w))) {
            return refuse(error, ps->line, "state %.32s: profile %d: THRUST_W %g outside the "
                          "vehicle's thruster (%g-%g W)", state->name, k, p->thrust_w,
                          b->min_thrust_w, b->max_thrust_w);
        }
        if (!(b->min_pitch_rad < p->pitch_rad && p->pitch_rad < b->max_pitch_rad)) {
            return refuse(error, ps->line, "state %.32s: profile %d: PITCH_RAD %g outside the "
                          "vehicle's (%g, %g) rad", state->name, k, p->pitch_rad,
                          b->min_pitch_rad, b->max_pitch_rad);
        }
        if (!(p->ballast_cc > least)) {
            return refuse(error, ps->line, "state %.32s: profile %d: BALLAST_CC %g does not "
                          "fly it: the vehicle needs more than %g cc", state->name, k,
                          p->ballast_cc, least);
        }
        if (p->ballast_cc > mission->max_ballast_cc) {
            return refuse(error, ps->line, "state %.32s: profile %d: BALLAST_CC %g exceeds "
                          "the vehicle's pump (%g cc)", state->name, k, p->ballast_cc,
                          mission->max_ballast_cc);
        }
        if (p->thrust_w == 0 && above(p->speed_mps, b->max_speed_mps)) {
            return refuse(error, ps->line, "state %.32s: profile %d: SPEED_MPS %g exceeds the "
                          "vehicle's fastest glide (%g m/s)", state->name, k, p->speed_mps,
                          b->max_speed_mps);
        }
    }
    return 0;
}

int gp_plan_check(const gp_plan *plan, const gp_mission *mission,
                  char error[GP_PLAN_ERROR_LEN])
{
    const gp_plan_bounds *b = mission->bounds != NULL ? mission->bounds : &contract_bounds;
    if (for_another_board(mission, plan->computer) && strcmp(plan->computer, GP_NO_BOARD) != 0) {
        return refuse(error, COMPUTER_LINE, "computer %s: the mission flies on board %.32s "
                      "(plan again with --computer %.32s)", plan->computer, b->board, b->board);
    }
    if (above(plan->budget_j, b->max_budget_j)) {
        return refuse(error, BUDGET_LINE, "budget_j %g J exceeds the mission's battery less "
                      "its reserve (%g J)", plan->budget_j, b->max_budget_j);
    }
    double states_j = 0;
    for (int s = 0; s < plan->n_states; s++) {
        states_j += plan->states[s].energy_j;
    }
    if (fabs(plan->predicted_j - states_j)
        > GP_PLAN_ROUNDING * fmax(plan->predicted_j, states_j)) {
        return refuse(error, PREDICTED_LINE, "predicted_j %g J is not the sum of its states' "
                      "energy (%g J)", plan->predicted_j, states_j);
    }
    if (!(plan->predicted_j > 0)) {
        return refuse(error, PREDICTED_LINE, "predicted_j 0 J: a flight draws energy");
    }
    if (above(plan->predicted_j, plan->budget_j)) {
        return refuse(error, PREDICTED_LINE, "predicted_j %g J exceeds budget_j %g J",
                      plan->predicted_j, plan->budget_j);
    }
    for (int s = 0; s < plan->n_states; s++) {
        const gp_state_bounds *sb = b->states != NULL ? &b->states[s] : NULL;
        if (check_state(&plan->states[s], &mission->states[s], sb, mission, b, error) < 0) {
            return -1;
        }
    }
    return 0;
}

/* ---- schedule ---------------------------------------------------------------- */

/* Shares of the cycle in index order; the last alternative with a share takes any
 * rounding remainder. Where one alternative has the whole cycle (most states) that is
 * the answer at any time, and the fmod (~55 instructions a tick) is not needed. */
static int alternative_at(const gp_plan_state *ps, double t_in_s)
{
    if (ps->n_profiles == 1) {  /* its share is 1: no loop */
        return 0;
    }
    int n_flown = 0, last_nonzero = 0;
    for (int i = 0; i < ps->n_profiles; i++) {
        if (ps->profiles[i].share > 0) {
            n_flown++;
            last_nonzero = i;
        }
    }
    if (n_flown < 2) {
        return last_nonzero;
    }
    double c = fmod(t_in_s, ps->cycle_s), start = 0;
    for (int i = 0; i < ps->n_profiles; i++) {
        double length = ps->profiles[i].share * ps->cycle_s;
        if (ps->profiles[i].share > 0 && c >= start && c < start + length) {
            return i;
        }
        start += length;
    }
    return last_nonzero;
}

void gp_schedule(const gp_state *state, const gp_plan_state *ps, double t_in_s,
                 double default_ballast_cc, gp_schedule_now *out)
{
    out->sensor_power = state->sensor_mask;
    out->profile = state->unplanned_profile;
    out->pitch_rad = NAN;
    out->ballast_cc = default_ballast_cc;
    out->speed_mps = NAN;
    out->thrust_w = NAN;
    if (ps == NULL) {
        return;
    }
    for (int i = 0; i < ps->n_sensors; i++) {
        const gp_plan_sensor *sensor = &ps->sensors[i];
        uint32_t bit = 1u << sensor->sensor;
        if (!(bit & GP_FLIGHT_SENSORS_MASK) && !(fmod(t_in_s, sensor->period_s) < sensor->on_s)) {
            out->sensor_power &= ~bit;
        }
    }
    out->profile = (uint8_t)alternative_at(ps, t_in_s);
    out->pitch_rad = ps->profiles[out->profile].pitch_rad;
    out->ballast_cc = ps->profiles[out->profile].ballast_cc;
    out->speed_mps = ps->profiles[out->profile].speed_mps;
    out->thrust_w = ps->profiles[out->profile].thrust_w;
}
