/* Unit tests of port/codec/hstpf_e2e: CRC vectors, protect, receiver rules. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "hstpf_e2e.h"

#define DID 0x1101u

/* Plain SAE J1850 (init 0xFF, final XOR 0xFF) vectors from the AUTOSAR CRC
 * library specification, and the catalogue check value of "123456789". */
static void test_crc8_sae_j1850_vectors(void **state)
{
    static const struct {
        const char *bytes;
        size_t n;
        uint8_t crc;
    } v[] = {
        {"\x00\x00\x00\x00", 4, 0x59}, {"\xF2\x01\x83", 3, 0x37},
        {"\x0F\xAA\x00\x55", 4, 0x79}, {"\x00\xFF\x55\x11", 4, 0xB8},
        {"\x33\x22\x55\xAA\xBB\xCC\xDD\xEE\xFF", 9, 0xCB},
        {"\x92\x6B\x55", 3, 0x8C},     {"\xFF\xFF\xFF\xFF", 4, 0x74},
        {"123456789", 9, 0x4B},
    };
    size_t i;
    (void)state;
    for (i = 0; i < sizeof v / sizeof v[0]; i++) {
        uint8_t c = (uint8_t)(hstpf_e2e_crc8(0xFFu, (const uint8_t *)v[i].bytes, v[i].n) ^ 0xFFu);
        assert_int_equal(c, v[i].crc);
    }
    /* Feeding in two parts gives the same register. */
    assert_int_equal(hstpf_e2e_crc8(hstpf_e2e_crc8(0xFFu, (const uint8_t *)"1234", 4), (const uint8_t *)"56789", 5) ^ 0xFFu,
                     0x4B);
    assert_int_equal(hstpf_e2e_crc8(0x5Au, NULL, 3), 0x5A);
}

/* Profile 1 frames (data ID mode BOTH, CRC byte 0, counter byte 1 low
 * nibble), cross-checked once against an independent Profile 1
 * implementation (PyPI autosar-e2e 1.0.0, e2e.p01.e2e_p01_protect). */
static void test_profile1_vectors(void **state)
{
    static const struct {
        uint16_t id;
        uint8_t f[8];
        uint8_t crc;
    } v[] = {
        {0x1101u, {0x00, 0x00, 0x12, 0x34, 0x56, 0x78, 0x9A, 0xBC}, 0x72},
        {0x1101u, {0x00, 0x10, 0xA0, 0x86, 0x01, 0x00, 0x00, 0x00}, 0x4D},
        {0x0000u, {0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00}, 0x00},
        {0x2101u, {0x00, 0x05, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00}, 0x21},
    };
    size_t i;
    (void)state;
    for (i = 0; i < sizeof v / sizeof v[0]; i++) {
        uint8_t f[8];
        memcpy(f, v[i].f, 8);
        assert_int_equal(hstpf_e2e_frame_crc(v[i].id, f, 8), v[i].crc);
        f[0] = 0xEE; /* the CRC byte itself is not covered */
        assert_int_equal(hstpf_e2e_frame_crc(v[i].id, f, 8), v[i].crc);
    }
    assert_int_equal(hstpf_e2e_frame_crc(DID, NULL, 8), 0);
    assert_int_equal(hstpf_e2e_frame_crc(DID, v[0].f, 1), 0);
}

static void test_protect_counter_and_crc(void **state)
{
    hstpf_e2e_tx_t tx;
    uint8_t f[8];
    unsigned k;
    (void)state;
    assert_int_equal(hstpf_e2e_tx_init(&tx, DID), 0);
    for (k = 0; k < 40; k++) {
        memset(f, 0, sizeof f);
        f[1] = 0xA0; /* a signal in the high nibble survives */
        f[2] = (uint8_t)k;
        assert_int_equal(hstpf_e2e_protect(&tx, f, 8), 0);
        assert_int_equal(f[1] & 0x0F, k % 15u); /* 0..14, 15 never sent */
        assert_int_equal(f[1] & 0xF0, 0xA0);
        assert_int_equal(f[0], hstpf_e2e_frame_crc(DID, f, 8));
    }
    /* Second vector above: counter 0, high nibble 1, position 100000 mm. */
    assert_int_equal(hstpf_e2e_tx_init(&tx, 0x1101u), 0);
    {
        uint8_t g[8] = {0, 0x10, 0xA0, 0x86, 0x01, 0, 0, 0};
        assert_int_equal(hstpf_e2e_protect(&tx, g, 8), 0);
        assert_int_equal(g[0], 0x4D);
    }
    assert_int_equal(hstpf_e2e_protect(NULL, f, 8), HSTPF_E2E_E_NULL);
    assert_int_equal(hstpf_e2e_protect(&tx, NULL, 8), HSTPF_E2E_E_NULL);
    assert_int_equal(hstpf_e2e_protect(&tx, f, 1), HSTPF_E2E_E_ARG);
    assert_int_equal(hstpf_e2e_tx_init(NULL, 1), HSTPF_E2E_E_NULL);
}

/* A receiver with max_delta 3, timeout 500 ms, and a helper that builds a
 * valid frame with a given counter. */
static hstpf_e2e_rx_t rx_new(void)
{
    hstpf_e2e_rx_config_t c;
    hstpf_e2e_rx_t rx;
    assert_int_equal(hstpf_e2e_rx_config_default(&c, DID, 8), 0);
    assert_int_equal(c.max_delta, 3);
    assert_int_equal(c.timeout_ms, 500);
    assert_int_equal(hstpf_e2e_rx_init(&rx, &c), 0);
    return rx;
}

static void frame(uint8_t f[8], uint8_t counter)
{
    memset(f, 0, 8);
    f[1] = counter;
    f[2] = 0x42;
    f[0] = hstpf_e2e_frame_crc(DID, f, 8);
}

static void test_rx_in_sequence_and_wrap(void **state)
{
    hstpf_e2e_rx_t rx = rx_new();
    uint8_t f[8];
    uint32_t t = 1000;
    unsigned k;
    (void)state;
    frame(f, 7);
    assert_int_equal(hstpf_e2e_rx_check(&rx, f, 8, t), HSTPF_E2E_OK_INITIAL);
    for (k = 1; k <= 30; k++) { /* 8..14, 0..14, ... wraps 14 -> 0 */
        t += 100;
        frame(f, (uint8_t)((7u + k) % 15u));
        assert_int_equal(hstpf_e2e_rx_check(&rx, f, 8, t), HSTPF_E2E_OK);
    }
    assert_int_equal(hstpf_e2e_rx_counts(&rx)->ok, 31);
    assert_int_equal(hstpf_e2e_rx_counts(&rx)->lost, 0);
    assert_int_equal(hstpf_e2e_rx_poll(&rx, t + 100), HSTPF_E2E_OK);
}

static void test_rx_faults_counted(void **state)
{
    hstpf_e2e_rx_t rx = rx_new();
    uint8_t f[8];
    const hstpf_e2e_counts_t *n = hstpf_e2e_rx_counts(&rx);
    (void)state;
    frame(f, 0);
    assert_int_equal(hstpf_e2e_rx_check(&rx, f, 8, 0), HSTPF_E2E_OK_INITIAL);
    /* Same counter again: repeated, reference unchanged. */
    assert_int_equal(hstpf_e2e_rx_check(&rx, f, 8, 100), HSTPF_E2E_REPEATED);
    /* Wrong length, whatever the content. */
    frame(f, 1);
    assert_int_equal(hstpf_e2e_rx_check(&rx, f, 7, 100), HSTPF_E2E_WRONG_LENGTH);
    /* One flipped payload bit: bad CRC. */
    f[5] ^= 0x04;
    assert_int_equal(hstpf_e2e_rx_check(&rx, f, 8, 100), HSTPF_E2E_BAD_CRC);
    /* Right data, wrong data ID (masquerade): bad CRC. */
    frame(f, 1);
    f[0] = hstpf_e2e_frame_crc(0x1102u, f, 8);
    assert_int_equal(hstpf_e2e_rx_check(&rx, f, 8, 100), HSTPF_E2E_BAD_CRC);
    /* The good frame 1 is still in sequence after all those rejections. */
    frame(f, 1);
    assert_int_equal(hstpf_e2e_rx_check(&rx, f, 8, 100), HSTPF_E2E_OK);
    /* 1 -> 3 (one lost) and 3 -> 6 (two lost): accepted, max_delta 3. */
    frame(f, 3);
    assert_int_equal(hstpf_e2e_rx_check(&rx, f, 8, 200), HSTPF_E2E_OK_LOST);
    frame(f, 6);
    assert_int_equal(hstpf_e2e_rx_check(&rx, f, 8, 300), HSTPF_E2E_OK_LOST);
    /* 6 -> 10 is a jump of 4: rejected, and 10 becomes the reference. */
    frame(f, 10);
    assert_int_equal(hstpf_e2e_rx_check(&rx, f, 8, 400), HSTPF_E2E_COUNTER_JUMP);
    frame(f, 11);
    assert_int_equal(hstpf_e2e_rx_check(&rx, f, 8, 450), HSTPF_E2E_OK);
    /* An old frame arriving late (reorder): 11 -> 9 is a jump of 13. */
    frame(f, 9);
    assert_int_equal(hstpf_e2e_rx_check(&rx, f, 8, 460), HSTPF_E2E_COUNTER_JUMP);
    /* Counter value 15 can never be sent: a jump, even with a good CRC. */
    frame(f, 15);
    assert_int_equal(hstpf_e2e_rx_check(&rx, f, 8, 470), HSTPF_E2E_COUNTER_JUMP);
    frame(f, 10);
    assert_int_equal(hstpf_e2e_rx_check(&rx, f, 8, 480), HSTPF_E2E_OK);

    assert_int_equal(n->ok, 6);
    assert_int_equal(n->lost, 3);
    assert_int_equal(n->repeated, 1);
    assert_int_equal(n->wrong_length, 1);
    assert_int_equal(n->bad_crc, 2);
    assert_int_equal(n->jump, 3);
    assert_int_equal(n->stale, 0);
}

static void test_rx_stale_and_resume(void **state)
{
    hstpf_e2e_rx_t rx = rx_new();
    uint8_t f[8];
    (void)state;
    /* Nothing yet: the first poll starts the clock. */
    assert_int_equal(hstpf_e2e_rx_poll(&rx, 10000), HSTPF_E2E_NO_DATA);
    assert_int_equal(hstpf_e2e_rx_poll(&rx, 10500), HSTPF_E2E_NO_DATA); /* not > timeout */
    assert_int_equal(hstpf_e2e_rx_poll(&rx, 10501), HSTPF_E2E_STALE);
    assert_int_equal(hstpf_e2e_rx_poll(&rx, 12000), HSTPF_E2E_STALE); /* counted once */
    assert_int_equal(hstpf_e2e_rx_counts(&rx)->stale, 1);
    assert_true(hstpf_e2e_rx_is_stale(&rx));
    frame(f, 4);
    assert_int_equal(hstpf_e2e_rx_check(&rx, f, 8, 12100), HSTPF_E2E_OK_INITIAL);
    assert_false(hstpf_e2e_rx_is_stale(&rx));
    /* A rejected frame does not keep the stream alive. */
    f[3] ^= 1;
    assert_int_equal(hstpf_e2e_rx_check(&rx, f, 8, 12500), HSTPF_E2E_BAD_CRC);
    assert_int_equal(hstpf_e2e_rx_poll(&rx, 12601), HSTPF_E2E_STALE);
    /* Silence noticed only by the next frame (no poll in between): the
     * stale episode is counted, and the frame resyncs whatever its counter. */
    frame(f, 5);
    assert_int_equal(hstpf_e2e_rx_check(&rx, f, 8, 13000), HSTPF_E2E_OK_INITIAL);
    frame(f, 12);
    assert_int_equal(hstpf_e2e_rx_check(&rx, f, 8, 14000), HSTPF_E2E_OK_INITIAL);
    assert_int_equal(hstpf_e2e_rx_counts(&rx)->stale, 3);
    assert_int_equal(hstpf_e2e_rx_counts(&rx)->jump, 0);
    /* Timestamps wrap round 2^32 ms. */
    {
        hstpf_e2e_rx_t r2 = rx_new();
        frame(f, 0);
        assert_int_equal(hstpf_e2e_rx_check(&r2, f, 8, 0xFFFFFF00u), HSTPF_E2E_OK_INITIAL);
        frame(f, 1);
        assert_int_equal(hstpf_e2e_rx_check(&r2, f, 8, 0x00000010u), HSTPF_E2E_OK); /* 272 ms later */
        assert_int_equal(hstpf_e2e_rx_poll(&r2, 0x00000200u), HSTPF_E2E_OK);
        assert_int_equal(hstpf_e2e_rx_poll(&r2, 0x00000205u), HSTPF_E2E_STALE);
        /* A timestamp from before the last frame is not a long gap. */
        hstpf_e2e_rx_t r3 = rx_new();
        frame(f, 0);
        assert_int_equal(hstpf_e2e_rx_check(&r3, f, 8, 5000), HSTPF_E2E_OK_INITIAL);
        assert_int_equal(hstpf_e2e_rx_poll(&r3, 4000), HSTPF_E2E_OK);
    }
}

static void test_rx_config_errors(void **state)
{
    hstpf_e2e_rx_config_t c;
    hstpf_e2e_rx_t rx;
    uint8_t f[8] = {0};
    (void)state;
    memset(&rx, 0x5A, sizeof rx);
    assert_int_equal(hstpf_e2e_rx_config_default(NULL, DID, 8), HSTPF_E2E_E_NULL);
    assert_int_equal(hstpf_e2e_rx_init(NULL, &c), HSTPF_E2E_E_NULL);
    assert_int_equal(hstpf_e2e_rx_config_default(&c, DID, 8), 0);
    assert_int_equal(hstpf_e2e_rx_init(&rx, NULL), HSTPF_E2E_E_NULL);
    c.max_delta = 0;
    assert_int_equal(hstpf_e2e_rx_init(&rx, &c), HSTPF_E2E_E_ARG);
    c.max_delta = 14; /* would accept any counter but a repeat */
    assert_int_equal(hstpf_e2e_rx_init(&rx, &c), HSTPF_E2E_E_ARG);
    c.max_delta = 13;
    c.timeout_ms = 0;
    assert_int_equal(hstpf_e2e_rx_init(&rx, &c), HSTPF_E2E_E_ARG);
    c.timeout_ms = 100;
    c.length = 1;
    assert_int_equal(hstpf_e2e_rx_init(&rx, &c), HSTPF_E2E_E_ARG);
    c.length = 65;
    assert_int_equal(hstpf_e2e_rx_init(&rx, &c), HSTPF_E2E_E_ARG);
    {
        /* rejected init left rx untouched */
        hstpf_e2e_rx_t ref;
        memset(&ref, 0x5A, sizeof ref);
        assert_memory_equal(&rx, &ref, sizeof rx);
    }
    c.length = 8;
    assert_int_equal(hstpf_e2e_rx_init(&rx, &c), 0);
    assert_int_equal(hstpf_e2e_rx_check(NULL, f, 8, 0), HSTPF_E2E_WRONG_LENGTH);
    assert_int_equal(hstpf_e2e_rx_check(&rx, NULL, 8, 0), HSTPF_E2E_WRONG_LENGTH);
    assert_int_equal(hstpf_e2e_rx_check(&rx, NULL, 0, 0), HSTPF_E2E_WRONG_LENGTH);
    assert_int_equal(hstpf_e2e_rx_counts(&rx)->wrong_length, 1); /* only the last was counted */
    assert_int_equal(hstpf_e2e_rx_poll(NULL, 0), HSTPF_E2E_STALE);
    assert_null(hstpf_e2e_rx_counts(NULL));
    assert_false(hstpf_e2e_rx_is_stale(NULL));
    assert_string_equal(hstpf_e2e_result_name(HSTPF_E2E_BAD_CRC), "bad_crc");
    assert_string_equal(hstpf_e2e_result_name((hstpf_e2e_result_t)99), "unknown");
    assert_true(hstpf_e2e_accepted(HSTPF_E2E_OK_LOST));
    assert_false(hstpf_e2e_accepted(HSTPF_E2E_REPEATED));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_crc8_sae_j1850_vectors), cmocka_unit_test(test_profile1_vectors),
        cmocka_unit_test(test_protect_counter_and_crc), cmocka_unit_test(test_rx_in_sequence_and_wrap),
        cmocka_unit_test(test_rx_faults_counted),      cmocka_unit_test(test_rx_stale_and_resume),
        cmocka_unit_test(test_rx_config_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
