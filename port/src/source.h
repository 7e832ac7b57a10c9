/* hstpfd: the two frame sources. Both feed hstpfd_core_frame() and
 * hstpfd_core_idle() and nothing else, so an offline replay of a log runs
 * the very code path that runs on the train. */
#ifndef HSTPFD_SOURCE_H
#define HSTPFD_SOURCE_H

#include <signal.h>
#include <stddef.h>

#include "core.h"

/* Why a run ended (the summary's "end"). */
#define HSTPFD_END_EOF "eof"
#define HSTPFD_END_SIGNAL "signal"
#define HSTPFD_END_ERROR "error"

/* Replays a candump log (portable C99 stdio). Returns 0 at the end of the
 * file or on *stop, -1 if the file cannot be opened or read (message on
 * stderr). *end is set to one of the HSTPFD_END_* strings. */
int hstpfd_run_log(hstpfd_core_t *c, const char *path, volatile sig_atomic_t *stop, const char **end);

/* Runs on a SocketCAN interface until *stop (Linux only; socketcan.c).
 * Returns 0 on *stop, -1 if SocketCAN is not available at all. */
int hstpfd_run_iface(hstpfd_core_t *c, const char *iface, volatile sig_atomic_t *stop, const char **end);

/* The sender for hstpfd_core_init() while hstpfd_run_iface() runs. */
int hstpfd_iface_send(void *ctx, const hstpfd_frame_t *f);

#endif
