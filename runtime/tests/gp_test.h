/* A tiny test harness: CHECK macros count failures; run_tests.c prints
 * "N passed, N failed" over the test functions. */
#ifndef GP_TEST_H
#define GP_TEST_H

#include <math.h>
#include <stdio.h>
#include <string.h>

void gp_test_fail(const char *file, int line, const char *what);

#define CHECK(cond)                                                     \
    do {                                                                \
        if (!(cond)) {                                                  \
            gp_test_fail(__FILE__, __LINE__, #cond);                    \
        }                                                               \
    } while (0)

#define CHECK_INT(actual, expected)                                     \
    do {                                                                \
        long long a_ = (long long)(actual), e_ = (long long)(expected); \
        if (a_ != e_) {                                                 \
            char m_[160];                                               \
            snprintf(m_, sizeof m_, "%s == %lld, expected %lld",        \
                     #actual, a_, e_);                                  \
            gp_test_fail(__FILE__, __LINE__, m_);                       \
        }                                                               \
    } while (0)

#define CHECK_NEAR(actual, expected, tolerance)                         \
    do {                                                                \
        double a_ = (actual), e_ = (expected);                          \
        if (!(fabs(a_ - e_) <= (tolerance))) {                          \
            char m_[160];                                               \
            snprintf(m_, sizeof m_, "%s == %.9g, expected %.9g",        \
                     #actual, a_, e_);                                  \
            gp_test_fail(__FILE__, __LINE__, m_);                       \
        }                                                               \
    } while (0)

#define CHECK_CONTAINS(text, part)                                      \
    do {                                                                \
        if (strstr((text), (part)) == NULL) {                           \
            char m_[400];                                               \
            snprintf(m_, sizeof m_, "'%.200s' lacks '%.100s'",          \
                     (text), (part));                                   \
            gp_test_fail(__FILE__, __LINE__, m_);                       \
        }                                                               \
    } while (0)

/* Deterministic pseudo-random numbers for noisy data and fuzzing (xorshift32). */
static inline unsigned gp_test_random(unsigned *state)
{
    unsigned x = *state;
    x ^= x << 13;
    x ^= x >> 17;
    x ^= x << 5;
    return *state = x;
}

#endif /* GP_TEST_H */
