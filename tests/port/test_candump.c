/* cmocka tests: candump log line parser and writer. */
#define _POSIX_C_SOURCE 200809L /* popen: the daemon run in test_sniff */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
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
        "(5.000000) vcan0 7FF#R4\n", /* the requested length survives */
        "(5.000000) vcan0 1ABCDEF0#R8\n",
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
        f.flags = HSTPFD_FRAME_RTR; /* no RTR frame asks for more than 8 bytes */
        f.len = 9;
        assert_int_equal(hstpfd_candump_format(&f, "vcan0", buf, sizeof buf), -1);
    }
}

/* Logs in other formats are refused with a hint, candump text passes. */
static void test_sniff(void **state)
{
    static const struct {
        const char *head;
        size_t n; /* 0: strlen */
        const char *format;
    } other[] = {
        {"date Mon Nov 23 01:00:00.000 am 2026\nbase hex  timestamps absolute\n"
         "   0.010000 1  123             Rx   d 8 00 11 22 33 44 55 66 77\n", 0, "Vector ASC"},
        {"LOGG\x90\0\0\0\x01\x02", 10, "Vector BLF"},
        {";$FILEVERSION=1.1\n;$STARTTIME=45000.1\n;\n"
         "     1)         0.1  Rx         0123  8  00 11 22 33 44 55 66 77\n", 0, "PEAK TRC"},
        {"timestamp,arbitration_id,extended,remote,error,dlc,data\n1.0,291,0,0,0,1,AA\n", 0,
         "python-can CSV"},
        {"MDF     4.10    ", 16, "ASAM MF4"},
        {"\x7f" "ELF\x02\x01\x01\0\0\0", 10, "binary"},
        {"hello\nworld\n", 0, "unknown"},
    };
    char msg[512];
    size_t i;
    (void)state;
    for (i = 0; i < sizeof other / sizeof other[0]; ++i) {
        const size_t n = other[i].n ? other[i].n : strlen(other[i].head);
        msg[0] = '\0';
        assert_int_equal(hstpfd_candump_sniff(other[i].head, n, "x.log", msg, sizeof msg), -1);
        assert_non_null(strstr(msg, "python -m can.logconvert"));
        assert_non_null(strstr(msg, other[i].format));
        assert_non_null(strstr(msg, "x.log"));
        assert_null(strchr(msg, '\n')); /* one line */
    }
    /* candump text, also after comments and a bad first line; empty files */
    {
        static const char *const ok[] = {"# c\n(1.0) vcan0 123#00\n", "garbage\n(1.0) vcan0 123#00", "",
                                         "; only a comment\n\n"};
        for (i = 0; i < sizeof ok / sizeof ok[0]; ++i) {
            assert_int_equal(hstpfd_candump_sniff(ok[i], strlen(ok[i]), "x", msg, sizeof msg), 0);
        }
    }
    /* files: stdin and unopenable files are left to the log source */
    assert_int_equal(hstpfd_candump_check_file("-", msg, sizeof msg), 0);
    assert_int_equal(hstpfd_candump_check_file("/nonexistent/x.asc", msg, sizeof msg), 0);
    {
        const char *path = HSTPFD_TEST_DIR "/test_candump.asc";
        FILE *fp = fopen(path, "wb");
        assert_non_null(fp);
        fputs(other[0].head, fp);
        fclose(fp);
        assert_int_equal(hstpfd_candump_check_file(path, msg, sizeof msg), -1);
        assert_non_null(strstr(msg, "Vector ASC"));
#ifdef HSTPFD_BIN
        { /* the daemon: non-zero exit, one line on stderr naming the converter */
            char cmd[1024], out[1024];
            FILE *pp;
            size_t got;
            int st;
            (void)snprintf(cmd, sizeof cmd, "'%s' --log '%s' 2>&1", HSTPFD_BIN, path);
            pp = popen(cmd, "r");
            assert_non_null(pp);
            got = fread(out, 1, sizeof out - 1, pp);
            out[got] = '\0';
            st = pclose(pp);
            assert_true(st != 0);
            assert_non_null(strstr(out, "python -m can.logconvert"));
            assert_ptr_equal(strchr(out, '\n'), out + got - 1);
        }
#endif
        remove(path);
    }
}

/* Every buffer too short for a line is refused, never overrun; the rarer
 * spellings and errors of the reader. */
static void test_sizes_and_spellings(void **state)
{
    static const char *const lines[] = {"(1.000000) vcan0 123#DEADBEEF\n",
                                        "(1.000000) vcan0 123##000112233445566778899AABB\n",
                                        "(1.000000) vcan0 20000004#R\n", "(1.000000) vcan0 123#R8\n"};
    char buf[256], part[256], ifc[4];
    hstpfd_frame_t f;
    size_t i;
    int n, k;
    (void)state;
    for (i = 0; i < sizeof lines / sizeof lines[0]; ++i) {
        assert_int_equal(hstpfd_candump_parse(lines[i], &f, NULL, 0), HSTPFD_CANDUMP_OK);
        n = hstpfd_candump_format(&f, "vcan0", buf, sizeof buf);
        assert_int_equal(n, (int)strlen(lines[i]));
        for (k = 0; k <= n; ++k) {
            memset(part, 'Z', sizeof part);
            assert_int_equal(hstpfd_candump_format(&f, "vcan0", part, (size_t)k), -1);
            assert_true(part[k] == 'Z');
        }
    }
    /* lower-case hex, 'r' and 't', tabs and other blanks, a short interface buffer */
    assert_int_equal(hstpfd_candump_parse("\t(2.5)\vcan_long_name\f1ab#deadbeef\tt\r\n", &f, ifc, sizeof ifc),
                     HSTPFD_CANDUMP_OK);
    assert_int_equal(f.id, 0x1AB);
    assert_int_equal(f.data[3], 0xEF);
    assert_string_equal(ifc, "can");
    assert_int_equal(hstpfd_candump_parse("(2.5) vcan0 1ab#r r", &f, ifc, 0), HSTPFD_CANDUMP_OK);
    assert_int_equal(f.flags, HSTPFD_FRAME_RTR);
    {
        static const char *const bad[] = {
            "(1234567890123.0) vcan0 123#00", /* 13 digits of seconds */
            "(1.0) vcan0 123##G0",            /* bad FD flags digit */
            "(1.0) vcan0 123#00_G",           /* bad len8_dlc digit */
            "(1.0) vcan0 123#R9",             /* RTR length above 8 */
            "(1.0) vcan0 123#00 r x",         /* junk after the direction */
            "(1.0) vcan0 123#00 Rx",          /* no blank after the direction */
            "(1.0) vcan0 G23#00",             /* no hex id */
            "(1.0) vcan0 123##",              /* FD without its flags digit */
            "(1.0) vcan0 123##1001122334455667788", /* 9 bytes: no FD length */
        };
        for (i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
            if (hstpfd_candump_parse(bad[i], &f, NULL, 0) != HSTPFD_CANDUMP_BAD) {
                fail_msg("accepted: %s", bad[i]);
            }
        }
    }
    assert_int_equal(hstpfd_candump_parse("(1.0) vcan0 123#00", NULL, NULL, 0), HSTPFD_CANDUMP_BAD);
    /* a negative time (a frame built by hand) is written with a negative second */
    memset(&f, 0, sizeof f);
    f.t_us = -1500000;
    f.id = 0x10;
    n = hstpfd_candump_format(&f, "c", buf, sizeof buf);
    assert_string_equal(buf, "(-2.500000) c 010#\n");
    assert_int_equal(n, (int)strlen(buf));
}

/* The sniffer on heads that end mid-line, lines too long for a frame, and
 * without a message buffer. */
static void test_sniff_edges(void **state)
{
    static char head[HSTPFD_CANDUMP_SNIFF_BYTES];
    char msg[256];
    (void)state;
    memset(head, 'x', sizeof head); /* one line longer than the head: not judged */
    assert_int_equal(hstpfd_candump_sniff(head, sizeof head, "x", msg, sizeof msg), 0);
    head[300] = '\n'; /* a 300-byte line, then the cut one */
    assert_int_equal(hstpfd_candump_sniff(head, sizeof head, "x", msg, sizeof msg), -1);
    assert_int_equal(hstpfd_candump_sniff(head, sizeof head, "x", NULL, 0), -1);
    assert_int_equal(hstpfd_candump_sniff("LOG", 3, "x", msg, sizeof msg), -1); /* too short for a magic */
    assert_non_null(strstr(msg, "unknown"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_classic),
        cmocka_unit_test(test_python_can_direction_and_ext),
        cmocka_unit_test(test_fd_rtr_err),
        cmocka_unit_test(test_skip_and_bad),
        cmocka_unit_test(test_format_roundtrip),
        cmocka_unit_test(test_sniff),
        cmocka_unit_test(test_sizes_and_spellings),
        cmocka_unit_test(test_sniff_edges),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
