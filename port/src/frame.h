/* hstpfd: one CAN frame as the daemon sees it, from a bus or a log.
 * Portable C99: no OS headers. Time is an integer number of microseconds
 * (the resolution of candump logs and of SO_TIMESTAMP), so differences are
 * exact and a replay is bit-for-bit reproducible. */
#ifndef HSTPFD_FRAME_H
#define HSTPFD_FRAME_H

#include <stdint.h>

#define HSTPFD_FRAME_EXT 0x01u /* 29-bit identifier */
#define HSTPFD_FRAME_RTR 0x02u /* remote request */
#define HSTPFD_FRAME_ERR 0x04u /* error frame: id holds the error class bits */
#define HSTPFD_FRAME_FD 0x08u  /* CAN FD frame */

#define HSTPFD_FRAME_MAX_DATA 64

/* Error classes of an error frame (the values of linux/can/error.h, which
 * are also what candump writes after the 0x20000000 error flag). */
#define HSTPFD_ERR_TX_TIMEOUT 0x001u
#define HSTPFD_ERR_LOSTARB 0x002u
#define HSTPFD_ERR_CRTL 0x004u
#define HSTPFD_ERR_PROT 0x008u
#define HSTPFD_ERR_TRX 0x010u
#define HSTPFD_ERR_ACK 0x020u
#define HSTPFD_ERR_BUSOFF 0x040u
#define HSTPFD_ERR_BUSERROR 0x080u
#define HSTPFD_ERR_RESTARTED 0x100u
#define HSTPFD_ERR_N_CLASSES 9

typedef struct {
    int64_t t_us;  /* receive time, microseconds (kernel stamp or log) */
    uint32_t id;   /* identifier without flags; error class bits if ERR */
    uint8_t flags; /* HSTPFD_FRAME_* */
    uint8_t len;   /* data bytes, 0..64 */
    uint8_t data[HSTPFD_FRAME_MAX_DATA];
} hstpfd_frame_t;

/* Name of error class bit i (0..HSTPFD_ERR_N_CLASSES-1), e.g. "bus_off". */
const char *hstpfd_err_class_name(unsigned i);

#endif
