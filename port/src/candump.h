/* hstpfd: candump log lines (candump -L / python-can "canutils" format):
 *
 *   (1700000000.123456) vcan0 123#DEADBEEF
 *   (1700000000.123456) vcan0 12345678#00 R        python-can adds R/T
 *   (1700000000.123456) vcan0 123##1DEADBEEF       CAN FD, flags digit
 *   (1700000000.123456) vcan0 123#R                remote request
 *   (1700000000.123456) vcan0 123#R4               remote request for 4 bytes
 *   (1700000000.123456) vcan0 20000080#0000000000000000   error frame
 *
 * Portable C99. */
#ifndef HSTPFD_CANDUMP_H
#define HSTPFD_CANDUMP_H

#include <stddef.h>

#include "frame.h"

enum {
    HSTPFD_CANDUMP_OK = 0,     /* a frame */
    HSTPFD_CANDUMP_EMPTY = 1,  /* blank line or comment (#, ;): skip */
    HSTPFD_CANDUMP_BAD = -1    /* malformed line */
};

/* Parses one line (with or without its newline). On OK fills *f and, if
 * iface is not NULL, copies the interface name (truncated to iface_size-1).
 * On BAD *f is unspecified. */
int hstpfd_candump_parse(const char *line, hstpfd_frame_t *f, char *iface, size_t iface_size);

/* Writes one frame as a candump -L line with a newline into buf. Returns
 * the length, or -1 if it does not fit. */
int hstpfd_candump_format(const hstpfd_frame_t *f, const char *iface, char *buf, size_t size);

/* Bytes of a file's head that hstpfd_candump_sniff() is given. */
#define HSTPFD_CANDUMP_SNIFF_BYTES 4096

/* Whether the first n bytes of a log (n <= HSTPFD_CANDUMP_SNIFF_BYTES) are
 * candump text: 0 if a line among them is a frame, or if there is nothing
 * but blank and comment lines; -1 if they hold NUL bytes or only lines that
 * are not frames (Vector ASC/BLF, PEAK TRC, CSV, MF4, ...), with a one-line
 * message in msg that names the file, the format guessed and
 * `python -m can.logconvert`. */
int hstpfd_candump_sniff(const char *head, size_t n, const char *name, char *msg, size_t msg_size);

/* hstpfd_candump_sniff() on the head of the file at path. 0 also for "-"
 * (stdin cannot be peeked) and for a file that cannot be opened (the log
 * source reports it). */
int hstpfd_candump_check_file(const char *path, char *msg, size_t msg_size);

#endif
