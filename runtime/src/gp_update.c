/* Plan updates (docs/plan-update.md): read an update, check it, make its changes in the
 * text of the plan in force and sign the result, as gliderplan.planner.update does, with
 * the same verdicts and words. Everything is bounded and static: at most 255 changes of
 * an update of at most GP_MAX_UPDATE_BYTES, lines of at most GP_MAX_PLAN_LINE_BYTES. */
#include "gp_update.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "gp_crc.h"
#include "gp_sha256.h"

#define TAG_BYTES GP_SHA256_SIZE
#define MIN_UPDATE_BYTES (GP_UPDATE_HEADER_BYTES + TAG_BYTES)
#define VARINT_BYTES 8        /* 56 bits: a line or a mantissa fits with room */
#define NUMBER_TEXT 48        /* gp_update_decimal_text's longest text and its NUL */
#define LINE_ROOM 512         /* a line of 255 bytes with six fields made 38 bytes longer */
#define MAX_MANTISSA 999999999999999LL  /* GP_UPDATE_MAX_DIGITS nines */

typedef struct {
    uint32_t line;      /* 1-based line of the plan file */
    uint8_t field;      /* gp_update_field */
    int64_t mantissa;
    int8_t exponent;
} change;

/* Each field's line keyword, the field's place after it (contract.UPDATE_FIELD_LINES) and
 * whether a line may leave it out (contract.UPDATE_OPTIONAL_FIELDS: then appended). */
static const struct {
    const char *keyword;
    uint8_t place;
    uint8_t optional;
} FIELD_LINES[] = {
    [GP_UF_STATE_CLOCK] = {"state", 2, 0},      [GP_UF_STATE_CYCLE] = {"state", 3, 0},
    [GP_UF_POWER_SLEEP] = {"power", 1, 0},      [GP_UF_POWER_CYCLES] = {"power", 2, 0},
    [GP_UF_SENSOR_PERIOD] = {"sensor", 2, 0},   [GP_UF_SENSOR_ON] = {"sensor", 3, 0},
    [GP_UF_PROFILE_SHARE] = {"profile", 2, 0},  [GP_UF_PROFILE_PITCH] = {"profile", 3, 0},
    [GP_UF_PROFILE_BALLAST] = {"profile", 4, 0}, [GP_UF_PROFILE_SPEED] = {"profile", 5, 0},
    [GP_UF_PROFILE_THRUST] = {"profile", 6, 1},
};
#define N_FIELD_CODES ((int)(sizeof FIELD_LINES / sizeof FIELD_LINES[0]))

static change changes[GP_UPDATE_MAX_CHANGES];

typedef struct {
    char *message;
    gp_update_status status;
} verdict;

static gp_update_status say(verdict *v, gp_update_status status, const char *format, ...)
{
    va_list args;
    va_start(args, format);
    vsnprintf(v->message, GP_UPDATE_MESSAGE_LEN, format, args);
    va_end(args);
    v->status = status;
    return status;
}

static uint32_t le32(const uint8_t *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

/* An LEB128 number at *at, before `end`, at most `most`. @return 0, or -1 (said). */
static int read_varint(verdict *v, const uint8_t *data, size_t *at, size_t end,
                       uint64_t most, int k, const char *what, uint64_t *out)
{
    uint64_t value = 0;
    for (int i = 0; i < VARINT_BYTES; i++) {
        if (*at + (size_t)i >= end) {
            say(v, GP_UPDATE_MALFORMED, "change %d: %s: the update ends inside it", k, what);
            return -1;
        }
        uint8_t byte = data[*at + (size_t)i];
        value |= (uint64_t)(byte & 0x7F) << (7 * i);
        if (!(byte & 0x80)) {
            if (value > most) {
                say(v, GP_UPDATE_MALFORMED, "change %d: %s: more than %llu", k, what,
                    (unsigned long long)most);
                return -1;
            }
            *at += (size_t)i + 1;
            *out = value;
            return 0;
        }
    }
    say(v, GP_UPDATE_MALFORMED, "change %d: %s: a number longer than %d bytes", k, what,
        VARINT_BYTES);
    return -1;
}

/* The changes of an update of `len` bytes into `changes`. @return their count, or -1. */
static int read_changes(verdict *v, const uint8_t *data, size_t len, int count)
{
    size_t end = len - TAG_BYTES, at = GP_UPDATE_HEADER_BYTES;
    uint32_t line = 0;
    for (int k = 1; k <= count; k++) {
        if (at >= end) {
            say(v, GP_UPDATE_MALFORMED, "change %d: the update ends before it", k);
            return -1;
        }
        uint8_t code = data[at];
        if (code == 0 || code >= N_FIELD_CODES) {
            say(v, GP_UPDATE_MALFORMED, "change %d: no field has code %u", k, (unsigned)code);
            return -1;
        }
        at++;
        uint64_t advance, raw;
        if (read_varint(v, data, &at, end, GP_MAX_PLAN_BYTES, k, "line", &advance) < 0
            || read_varint(v, data, &at, end, 2 * (uint64_t)MAX_MANTISSA, k, "value", &raw)
                   < 0) {
            return -1;
        }
        if (at >= end) {
            say(v, GP_UPDATE_MALFORMED, "change %d: the update ends inside it", k);
            return -1;
        }
        int exponent = (int8_t)data[at++];
        int64_t mantissa = raw % 2 == 0 ? (int64_t)(raw / 2) : -(int64_t)((raw + 1) / 2);
        if (exponent < -GP_UPDATE_MAX_EXPONENT || exponent > GP_UPDATE_MAX_EXPONENT
            || (mantissa == 0 && exponent != 0) || (mantissa != 0 && mantissa % 10 == 0)) {
            say(v, GP_UPDATE_MALFORMED, "change %d: the value is not a canonical decimal", k);
            return -1;
        }
        if (advance == 0 && (k == 1 || code <= changes[k - 2].field)) {
            say(v, GP_UPDATE_MALFORMED, "change %d: changes must come in the order of the "
                "plan's lines and fields", k);
            return -1;
        }
        line += (uint32_t)advance;
        changes[k - 1] = (change){line, code, mantissa, (int8_t)exponent};
    }
    if (at != end) {
        say(v, GP_UPDATE_MALFORMED, "%lu bytes after the last change", (unsigned long)(end - at));
        return -1;
    }
    return count;
}

size_t gp_update_decimal_text(int64_t mantissa, int exponent, char *text)
{
    char digits[24];
    unsigned long long magnitude = mantissa < 0 ? 0ULL - (unsigned long long)mantissa
                                                : (unsigned long long)mantissa;
    int n = snprintf(digits, sizeof digits, "%llu", magnitude);
    size_t at = 0;
    if (mantissa == 0) {
        memcpy(text, "0", 2);
        return 1;
    }
    if (mantissa < 0) {
        text[at++] = '-';
    }
    if (exponent >= 0) {
        memcpy(text + at, digits, (size_t)n);
        at += (size_t)n;
        for (int i = 0; i < exponent; i++) {
            text[at++] = '0';
        }
    } else if (n + exponent > 0) {
        int point = n + exponent;
        memcpy(text + at, digits, (size_t)point);
        at += (size_t)point;
        text[at++] = '.';
        memcpy(text + at, digits + point, (size_t)(n - point));
        at += (size_t)(n - point);
    } else {
        text[at++] = '0';
        text[at++] = '.';
        for (int i = 0; i < -(n + exponent); i++) {
            text[at++] = '0';
        }
        memcpy(text + at, digits, (size_t)n);
        at += (size_t)n;
    }
    text[at] = '\0';
    return at;
}

/* The new plan file as it is written: bytes past the capacity are counted, not kept. */
typedef struct {
    char *out;
    size_t len;
    int overflow;
} writer;

static void put(writer *w, const char *bytes, size_t n)
{
    if (w->overflow || w->len + n > GP_MAX_PLAN_BYTES) {
        w->overflow = 1;
        return;
    }
    memcpy(w->out + w->len, bytes, n);
    w->len += n;
}

/* `line` (`len` bytes, no LF) with field `place` set to `value`, in `room` (LINE_ROOM);
 * an `optional` field the line leaves out (it ends one field before) is appended.
 * @return the new length, or -1 if the line has no such field */
static long set_field(const char *line, size_t len, int place, int optional,
                      const char *value, char *room)
{
    size_t start = 0;
    for (int field = 0; field < place; field++) {
        const char *space = memchr(line + start, ' ', len - start);
        if (!space) {
            size_t n = strlen(value);
            if (!optional || field != place - 1 || len + 1 + n >= LINE_ROOM) {
                return -1;
            }
            char copy[LINE_ROOM];
            memcpy(copy, line, len);
            memcpy(room, copy, len);
            room[len] = ' ';
            memcpy(room + len + 1, value, n);
            return (long)(len + 1 + n);
        }
        start = (size_t)(space - line) + 1;
    }
    const char *space = memchr(line + start, ' ', len - start);
    size_t stop = space ? (size_t)(space - line) : len;
    size_t n = strlen(value);
    if (start + n + (len - stop) >= LINE_ROOM) {
        return -1;  /* cannot happen: LINE_ROOM holds six longest values on a 255-byte line */
    }
    char copy[LINE_ROOM];
    memcpy(copy, line, len);
    memcpy(room, copy, start);
    memcpy(room + start, value, n);
    memcpy(room + start + n, copy + stop, len - stop);
    return (long)(start + n + (len - stop));
}

/* The first word of a line is `keyword`. */
static int keyword_is(const char *line, size_t len, const char *keyword)
{
    size_t n = strlen(keyword);
    return len >= n && memcmp(line, keyword, n) == 0 && (len == n || line[n] == ' ');
}

/* The held plan without its signature lines: @return the length of its unsigned part. */
static size_t unsigned_length(const char *held, size_t len)
{
    size_t starts[3] = {0, 0, 0};  /* of the last three lines */
    int found = 0;
    for (size_t i = len; i > 0 && found < 3; i--) {
        if (i - 1 == 0 || held[i - 2] == '\n') {
            starts[found++] = i - 1;
        }
    }
    if (found == 3 && len - starts[1] >= 5 && memcmp(held + starts[1], "seq ", 4) == 0
        && memcmp(held + starts[0], "hmac ", 5) == 0) {
        return starts[1];
    }
    return len;
}

/* Make the `count` changes in the held plan's text, then its checksum and signature. */
static gp_update_status make_plan(verdict *v, const char *held, size_t held_len, int count,
                                  uint32_t new_seq, const uint8_t *key, writer *w)
{
    static char room[LINE_ROOM];
    size_t end = unsigned_length(held, held_len);
    uint32_t body_lines = 0;
    for (size_t i = 0; i < end; i++) {
        body_lines += held[i] == '\n';
    }
    body_lines = body_lines > 0 ? body_lines - 1 : 0;  /* the crc32 line is not body */
    int next = 0;
    size_t at = 0;
    for (uint32_t number = 1; number <= body_lines; number++) {
        const char *lf = memchr(held + at, '\n', end - at);
        size_t len = (size_t)(lf - (held + at));
        const char *line = held + at;
        for (; next < count && changes[next].line == number; next++) {
            const change *c = &changes[next];
            char value[NUMBER_TEXT];
            gp_update_decimal_text(c->mantissa, c->exponent, value);
            long made = keyword_is(line, len, FIELD_LINES[c->field].keyword)
                            ? set_field(line, len, FIELD_LINES[c->field].place,
                                        FIELD_LINES[c->field].optional, value, room)
                            : -1;
            if (made < 0) {
                return say(v, GP_UPDATE_MALFORMED, "change %d: line %lu is no '%s' line with "
                           "a field %u", next + 1, (unsigned long)number,
                           FIELD_LINES[c->field].keyword, (unsigned)FIELD_LINES[c->field].place);
            }
            line = room;
            len = (size_t)made;
        }
        put(w, line, len);
        put(w, "\n", 1);
        at = (size_t)(lf - held) + 1;
    }
    if (next < count) {
        return say(v, GP_UPDATE_MALFORMED, "change %d: line %lu is not in the plan's body "
                   "(lines 1..%lu)", next + 1, (unsigned long)changes[next].line,
                   (unsigned long)body_lines);
    }
    char tail[96];
    int n = snprintf(tail, sizeof tail, "crc32 %08lx\nseq %lu\n",
                     (unsigned long)gp_crc32(0, (const uint8_t *)w->out,
                                             w->overflow ? 0 : w->len),
                     (unsigned long)new_seq);
    put(w, tail, (size_t)n);
    if (w->overflow) {
        return say(v, GP_UPDATE_BAD_PLAN, "the updated plan would have more than %d bytes",
                   GP_MAX_PLAN_BYTES);
    }
    gp_hmac_sha256 mac;
    uint8_t tag[GP_SHA256_SIZE];
    gp_hmac_sha256_init(&mac, key, GP_PLAN_KEY_BYTES);
    gp_hmac_sha256_update(&mac, w->out, w->len);
    gp_hmac_sha256_final(&mac, tag);
    put(w, "hmac ", 5);
    for (int i = 0; i < GP_SHA256_SIZE; i++) {
        char hex[3];
        snprintf(hex, sizeof hex, "%02x", tag[i]);
        put(w, hex, 2);
    }
    put(w, "\n", 1);
    if (w->overflow) {
        return say(v, GP_UPDATE_BAD_PLAN, "the updated plan would have more than %d bytes",
                   GP_MAX_PLAN_BYTES);
    }
    return GP_UPDATE_APPLIED;
}

static void plan_hash(const void *data, size_t len, uint8_t out[GP_SHA256_SIZE])
{
    gp_sha256 sha;
    gp_sha256_init(&sha);
    gp_sha256_update(&sha, data, len);
    gp_sha256_final(&sha, out);
}

gp_update_status gp_update_apply(const uint8_t *update, size_t len, const char *held,
                                 size_t held_len, const gp_plan_auth *auth,
                                 const gp_mission *mission, char *out, size_t *out_len,
                                 gp_plan *plan, char message[GP_UPDATE_MESSAGE_LEN])
{
    verdict v = {message, GP_UPDATE_APPLIED};
    if (!auth) {
        return say(&v, GP_UPDATE_NO_KEY, "no key is provisioned on this vehicle: plan updates "
                   "are refused (start the runtime with --key FILE)");
    }
    if (len > GP_MAX_UPDATE_BYTES) {
        return say(&v, GP_UPDATE_MALFORMED, "the update has %lu bytes, more than %d",
                   (unsigned long)len, GP_MAX_UPDATE_BYTES);
    }
    if (len < MIN_UPDATE_BYTES || update[0] != 'G' || update[1] != 'U') {
        return say(&v, GP_UPDATE_MALFORMED, "not a plan update (%lu bytes%s", (unsigned long)len,
                   len >= 2 ? ", no GU magic)" : ")");
    }
    if (update[2] != GP_UPDATE_FORMAT_VERSION) {
        return say(&v, GP_UPDATE_MALFORMED, "update version %u: this vehicle reads version %d",
                   (unsigned)update[2], GP_UPDATE_FORMAT_VERSION);
    }
    uint32_t base_seq = le32(update + 3), new_seq = le32(update + 7);
    const uint8_t *base_hash = update + 11, *result_hash = update + 11 + GP_UPDATE_HASH_BYTES;
    int count = read_changes(&v, update, len, update[GP_UPDATE_HEADER_BYTES - 1]);
    if (count < 0) {
        return v.status;
    }
    gp_hmac_sha256 mac;
    uint8_t tag[GP_SHA256_SIZE];
    gp_hmac_sha256_init(&mac, auth->key, GP_PLAN_KEY_BYTES);
    gp_hmac_sha256_update(&mac, update, len - TAG_BYTES);
    gp_hmac_sha256_final(&mac, tag);
    if (!gp_tags_equal(tag, update + len - TAG_BYTES)) {
        return say(&v, GP_UPDATE_FORGED, "the signature does not match: the update was changed "
                   "after it was signed, or signed with another key");
    }
    uint32_t seq = held && held_len ? auth->last_seq : 0;
    if (seq == 0) {
        return say(&v, GP_UPDATE_NOT_HELD, "no signed plan is in force: send a whole plan "
                   "first");
    }
    uint8_t digest[GP_SHA256_SIZE];
    plan_hash(held, held_len, digest);
    if (new_seq <= seq) {
        if (new_seq == seq && memcmp(result_hash, digest, GP_UPDATE_HASH_BYTES) == 0) {
            return say(&v, GP_UPDATE_DUPLICATE, "update to plan %lu already applied: plan %lu "
                       "is in force", (unsigned long)seq, (unsigned long)seq);
        }
        return say(&v, GP_UPDATE_STALE, "update to plan %lu is not newer than plan %lu in "
                   "force: replayed or stale", (unsigned long)new_seq, (unsigned long)seq);
    }
    if (base_seq > seq) {
        return say(&v, GP_UPDATE_OUT_OF_ORDER, "the update was made against plan %lu, newer "
                   "than plan %lu in force: an update before it has not arrived",
                   (unsigned long)base_seq, (unsigned long)seq);
    }
    if (base_seq < seq) {
        return say(&v, GP_UPDATE_NOT_HELD, "the update was made against plan %lu; plan %lu "
                   "is in force", (unsigned long)base_seq, (unsigned long)seq);
    }
    if (memcmp(base_hash, digest, GP_UPDATE_HASH_BYTES) != 0) {
        return say(&v, GP_UPDATE_NOT_HELD, "the update was made against another plan %lu: its "
                   "hash differs from the plan in force", (unsigned long)seq);
    }
    writer w = {out, 0, 0};
    if (make_plan(&v, held, held_len, count, new_seq, auth->key, &w) != GP_UPDATE_APPLIED) {
        return v.status;
    }
    *out_len = w.len;
    plan_hash(out, w.len, digest);
    if (memcmp(result_hash, digest, GP_UPDATE_HASH_BYTES) != 0) {
        return say(&v, GP_UPDATE_MALFORMED, "the plan it makes is not the plan it was signed "
                   "for (its hash differs)");
    }
    char error[GP_PLAN_ERROR_LEN];
    if (gp_plan_read(out, w.len, mission, auth, plan, error) < 0) {
        return say(&v, GP_UPDATE_BAD_PLAN, "the updated plan is refused: %s", error);
    }
    return say(&v, GP_UPDATE_APPLIED, "ok: plan %lu in force", (unsigned long)new_seq);
}
