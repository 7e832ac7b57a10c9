/* cmocka tests: candump log line parser and writer. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "candump.h"

static void test_classic(void **state)
{
    hstpfd_frame_t f;
    char ifc[16];
    (void)state;
    assert_int_equal(hstpfd_candump_parse("(1700000000.123456) vcan0 123#DEADBEEF\n", &f, ifc, sizeof ifc),
                     HSTPFD_CANDUMP_OK);
    assert_true(f.t_us == INT64_C(1700000000123456));
    assert_int_equal(f.id, 0x123);
    assert_int_equal(f.flags, 0);
    assert_int_equal(f.len, 4);
    assert_int_equal(f.data[0], 0xDE);
    assert_int_equal(f.data[3], 0xEF);
    assert_string_equal(ifc, "vcan0");
}

static void test_python_can_direction_and_ext(void **state)
{
    hstpfd_frame_t f;
    (void)state;
    assert_int_equal(hstpfd_candump_parse("(12.5) can1 18FF0102#0102030405060708 R", &f, NULL, 0),
                     HSTPFD_CANDUMP_OK);
    assert_true(f.t_us == INT64_C(12500000));
    assert_int_equal(f.id, 0x18FF0102);
    assert_int_equal(f.flags, HSTPFD_FRAME_EXT);
    assert_int_equal(f.len, 8);
    assert_int_equal(f.data[7], 8);
    assert_int_equal(hstpfd_candump_parse("(0.000001) vcan0 7FF# T\r\n", &f, NULL, 0), HSTPFD_CANDUMP_OK);
    assert_int_equal(f.len, 0);
    assert_true(f.t_us == 1);
    /* more than six fraction digits: truncated to microseconds */
    assert_int_equal(hstpfd_candump_parse("(3.1234567) vcan0 001#00", &f, NULL, 0), HSTPFD_CANDUMP_OK);
    assert_true(f.t_us == INT64_C(3123456));
}

static void test_fd_rtr_err(void **state)
{
    hstpfd_frame_t f;
    (void)state;
    assert_int_equal(hstpfd_candump_parse("(1.0) vcan0 123##1" "00112233445566778899AABB", &f, NULL, 0),
                     HSTPFD_CANDUMP_OK);
    assert_int_equal(f.flags, HSTPFD_FRAME_FD);
    assert_int_equal(f.len, 12);
    assert_int_equal(hstpfd_candump_parse("(1.0) vcan0 123##1" "001122334455667788", &f, NULL, 0),
                     HSTPFD_CANDUMP_BAD); /* 9 bytes is no FD length */
    assert_int_equal(hstpfd_candump_parse("(1.0) vcan0 123#R", &f, NULL, 0), HSTPFD_CANDUMP_OK);
    assert_int_equal(f.flags, HSTPFD_FRAME_RTR);
    assert_int_equal(hstpfd_candump_parse("(1.0) vcan0 123#R4", &f, NULL, 0), HSTPFD_CANDUMP_OK);
    assert_int_equal(f.len, 4);
    assert_int_equal(hstpfd_candump_parse("(1.0) vcan0 20000044#0000000000000000", &f, NULL, 0),
                     HSTPFD_CANDUMP_OK);
    assert_int_equal(f.flags, HSTPFD_FRAME_ERR);
    assert_int_equal(f.id, HSTPFD_ERR_BUSOFF | HSTPFD_ERR_CRTL);
    /* candump's dotted data and len8_dlc suffix */
    assert_int_equal(hstpfd_candump_parse("(1.0) vcan0 123#01.02.03", &f, NULL, 0), HSTPFD_CANDUMP_OK);
    assert_int_equal(f.len, 3);
    assert_int_equal(hstpfd_candump_parse("(1.0) vcan0 123#0102030405060708_C", &f, NULL, 0),
                     HSTPFD_CANDUMP_OK);
}

static void test_skip_and_bad(void **state)
{
    hstpfd_frame_t f;
    static const char *const bad[] = {
        "vcan0 123#00",                        /* no time */
        "(1.0 vcan0 123#00",                   /* no ')' */
        "(.5) vcan0 123#00",                   /* no seconds */
        "(1.) vcan0 123#00",                   /* no fraction digits */
        "(1.0)vcan0 123#00",                   /* no blank */
        "(1.0) vcan0",                         /* no frame */
        "(1.0) vcan0 123",                     /* no '#' */
        "(1.0) vcan0 800#00",                  /* 11-bit id too big */
        "(1.0) vcan0 123#0",                   /* odd digits */
        "(1.0) vcan0 123#0G",                  /* bad hex */
        "(1.0) vcan0 123#001122334455667788",  /* 9 bytes, classic */
        "(1.0) vcan0 123456789#00",            /* 9-digit id */
        "(1.0) vcan0 123#00 X",                /* junk after the frame */
        "(1.0) vcan0 123#00 R T",              /* two directions */
        "(1.0) vcan0 #00",                     /* no id */
    };
    size_t i;
    (void)state;
    assert_int_equal(hstpfd_candump_parse("", &f, NULL, 0), HSTPFD_CANDUMP_EMPTY);
    assert_int_equal(hstpfd_candump_parse("   \n", &f, NULL, 0), HSTPFD_CANDUMP_EMPTY);
    assert_int_equal(hstpfd_candump_parse("# comment", &f, NULL, 0), HSTPFD_CANDUMP_EMPTY);
    for (i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        if (hstpfd_candump_parse(bad[i], &f, NULL, 0) != HSTPFD_CANDUMP_BAD) {
            fail_msg("accepted: %s", bad[i]);
        }
    }
    assert_int_equal(hstpfd_candump_parse(NULL, &f, NULL, 0), HSTPFD_CANDUMP_BAD);
}

static void test_format_roundtrip(void **state)
{
    static const char *const lines[] = {
        "(1700000000.000001) vcan0 123#DEADBEEF\n",
        "(1700000000.999999) vcan0 1ABCDEF0#0011\n",
        "(0.500000) can0 000#\n",
        "(5.000000) vcan0 20000040#0000000000000000\n",
        "(5.000000) vcan0 7FF#R\n",
    };
    char buf[256];
    size_t i;
    (void)state;
    for (i = 0; i < sizeof lines / sizeof lines[0]; ++i) {
        hstpfd_frame_t f;
        char ifc[16];
        assert_int_equal(hstpfd_candump_parse(lines[i], &f, ifc, sizeof ifc), HSTPFD_CANDUMP_OK);
        assert_int_equal(hstpfd_candump_format(&f, ifc, buf, sizeof buf), (int)strlen(lines[i]));
        assert_string_equal(buf, lines[i]);
    }
    {
        hstpfd_frame_t f;
        assert_int_equal(hstpfd_candump_parse(lines[0], &f, NULL, 0), HSTPFD_CANDUMP_OK);
        assert_int_equal(hstpfd_candump_format(&f, "vcan0", buf, 20), -1);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_classic),
        cmocka_unit_test(test_python_can_direction_and_ext),
        cmocka_unit_test(test_fd_rtr_err),
        cmocka_unit_test(test_skip_and_bad),
        cmocka_unit_test(test_format_roundtrip),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
