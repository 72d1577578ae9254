/* SHA-256 against the FIPS 180 examples and HMAC-SHA256 against RFC 4231's test cases,
 * fed whole and in uneven pieces (every block boundary of the padding is crossed). */
#include "gp_sha256.h"
#include "gp_test.h"

static void hex(const uint8_t *bytes, size_t n, char *out)
{
    for (size_t i = 0; i < n; i++) {
        snprintf(out + 2 * i, 3, "%02x", bytes[i]);
    }
}

static void check_sha256(const uint8_t *message, size_t len, size_t piece, const char *expected)
{
    gp_sha256 ctx;
    uint8_t digest[GP_SHA256_SIZE];
    char text[2 * GP_SHA256_SIZE + 1];
    gp_sha256_init(&ctx);
    for (size_t at = 0; at < len; at += piece) {
        gp_sha256_update(&ctx, message + at, len - at < piece ? len - at : piece);
    }
    gp_sha256_final(&ctx, digest);
    hex(digest, sizeof digest, text);
    CHECK_CONTAINS(text, expected);
}

void test_sha256_should_match_the_fips_180_examples(void)
{
    static uint8_t million[1000000];
    const char *two_blocks = "abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq";
    for (size_t piece = 1; piece <= 65; piece += 16) {
        check_sha256((const uint8_t *)"abc", 3, piece,
                     "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
        check_sha256((const uint8_t *)"", 0, piece,
                     "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
        check_sha256((const uint8_t *)two_blocks, strlen(two_blocks), piece,
                     "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
    }
    memset(million, 'a', sizeof million);
    check_sha256(million, sizeof million, 4093,
                 "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
}

void test_hmac_sha256_should_match_rfc_4231(void)
{
    static const char *data[] = {
        "Hi There", "what do ya want for nothing?", NULL, NULL, "Test With Truncation",
        "Test Using Larger Than Block-Size Key - Hash Key First",
        "This is a test using a larger than block-size key and a larger than block-size "
        "data. The key needs to be hashed before being used by the HMAC algorithm."};
    static const char *tags[] = {  /* case 5's tag is truncated to 128 bits in the RFC */
        "b0344c61d8db38535ca8afceaf0bf12b881dc200c9833da726e9376c2e32cff7",
        "5bdcc146bf60754e6a042426089575c75a003f089d2739839dec58b964ec3843",
        "773ea91e36800e46854db8ebd09181a72959098b3ef8c122d9635514ced565fe",
        "82558a389a443c0ea4cc819899f2083a85f0faa3e578f8077a2e3ff46729665b",
        "a3b6167473100ee06e0c796c2955552b",
        "60e431591ee0b67f0d8a26aacbf5b77f8e0bc6213728c5140546040f0ee37f54",
        "9b09ffa71b942fcb27635fbcd5b0e944bfdc63644f0713938a7f51535c3a35e2"};
    uint8_t key[131], message[50];
    for (int c = 0; c < 7; c++) {
        size_t key_len = c == 1 ? 4 : c >= 5 ? 131 : c == 3 ? 25 : 20;
        for (size_t i = 0; i < key_len; i++) {
            key[i] = c == 0 ? 0x0b : c == 2 || c >= 5 ? 0xaa : c == 3 ? (uint8_t)(i + 1) : 0x0c;
        }
        if (c == 1) {
            memcpy(key, "Jefe", 4);
        }
        const uint8_t *msg = (const uint8_t *)data[c];
        size_t len = msg ? strlen(data[c]) : sizeof message;
        if (!msg) {
            memset(message, c == 2 ? 0xdd : 0xcd, sizeof message);
            msg = message;
        }
        gp_hmac_sha256 ctx;
        uint8_t tag[GP_SHA256_SIZE];
        char text[2 * GP_SHA256_SIZE + 1];
        gp_hmac_sha256_init(&ctx, key, key_len);
        gp_hmac_sha256_update(&ctx, msg, len / 3);  /* in two pieces */
        gp_hmac_sha256_update(&ctx, msg + len / 3, len - len / 3);
        gp_hmac_sha256_final(&ctx, tag);
        hex(tag, sizeof tag, text);
        CHECK(strncmp(text, tags[c], strlen(tags[c])) == 0);
    }
}

void test_tags_should_compare_every_byte(void)
{
    uint8_t a[GP_SHA256_SIZE] = {0}, b[GP_SHA256_SIZE] = {0};
    CHECK(gp_tags_equal(a, b));
    for (int i = 0; i < GP_SHA256_SIZE; i++) {
        b[i] = 1;
        CHECK(!gp_tags_equal(a, b));
        b[i] = 0;
    }
}
