/* hstpfd: SocketCAN I/O (Linux only). Opens the interface with kernel
 * filters for our input IDs, error frames enabled and kernel receive
 * timestamps, polls with timeouts, sends, and closes and reopens the
 * socket when the interface goes away. Everything else is in core*.c. */
#define _DEFAULT_SOURCE 1

#include <errno.h>
#include <fcntl.h>
#include <net/if.h>
#include <poll.h>
#include <stdio.h>
#include <string.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <sys/uio.h>
#include <time.h>
#include <unistd.h>

#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>

#include "source.h"

typedef struct {
    int fd;
    hstpfd_core_t *core;
} io_t;

static io_t io = {-1, NULL};

static int64_t now_realtime_us(void)
{
    struct timespec ts;
    (void)clock_gettime(CLOCK_REALTIME, &ts);
    return (int64_t)ts.tv_sec * 1000000 + ts.tv_nsec / 1000;
}

static int64_t now_mono_us(void)
{
    struct timespec ts;
    (void)clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000000 + ts.tv_nsec / 1000;
}

/* A socket on iface, bound, filtered, stamped, non-blocking; -1 with errno. */
static int open_iface(const char *iface, hstpfd_rx_filter_t filter)
{
    struct sockaddr_can addr;
    struct ifreq ifr;
    struct can_filter flt[HSTPFD_N_INPUTS];
    const can_err_mask_t err_mask = CAN_ERR_MASK;
    const int on = 1;
    unsigned i;
    int fd, e, fl;

    fd = socket(PF_CAN, SOCK_RAW, CAN_RAW);
    if (fd < 0) {
        return -1;
    }
    memset(&ifr, 0, sizeof ifr);
    (void)snprintf(ifr.ifr_name, sizeof ifr.ifr_name, "%s", iface);
    if (ioctl(fd, SIOCGIFINDEX, &ifr) < 0) {
        goto fail;
    }
    memset(&addr, 0, sizeof addr);
    addr.can_family = AF_CAN;
    addr.can_ifindex = ifr.ifr_ifindex;
    if (ioctl(fd, SIOCGIFFLAGS, &ifr) < 0) {
        goto fail;
    }
    if (!(ifr.ifr_flags & IFF_UP)) {
        errno = ENETDOWN;
        goto fail;
    }
    if (filter == HSTPFD_RX_FILTER_INPUTS) {
        for (i = 0; i < HSTPFD_N_INPUTS; ++i) { /* exactly these 11-bit data frames */
            flt[i].can_id = hstpfd_input_id(i);
            flt[i].can_mask = CAN_SFF_MASK | CAN_EFF_FLAG | CAN_RTR_FLAG;
        }
        if (setsockopt(fd, SOL_CAN_RAW, CAN_RAW_FILTER, flt, (socklen_t)(HSTPFD_N_INPUTS * sizeof flt[0])) < 0) {
            goto fail;
        }
    } else if (filter == HSTPFD_RX_FILTER_BLOCK) {
        flt[0].can_id = 0x100u; /* 0x100..0x1FF, any format (odd ones are counted) */
        flt[0].can_mask = 0x700u;
        if (setsockopt(fd, SOL_CAN_RAW, CAN_RAW_FILTER, flt, (socklen_t)sizeof flt[0]) < 0) {
            goto fail;
        }
    }
    if (setsockopt(fd, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &err_mask, (socklen_t)sizeof err_mask) < 0 ||
        setsockopt(fd, SOL_SOCKET, SO_TIMESTAMP, &on, (socklen_t)sizeof on) < 0) {
        goto fail;
    }
    if (bind(fd, (struct sockaddr *)(void *)&addr, (socklen_t)sizeof addr) < 0) {
        goto fail;
    }
    fl = fcntl(fd, F_GETFL, 0);
    if (fl < 0 || fcntl(fd, F_SETFL, fl | O_NONBLOCK) < 0) {
        goto fail;
    }
    return fd;
fail:
    e = errno;
    (void)close(fd);
    errno = e;
    return -1;
}

static void to_frame(const struct can_frame *cf, int64_t t_us, hstpfd_frame_t *f)
{
    memset(f, 0, sizeof *f);
    f->t_us = t_us;
    if (cf->can_id & CAN_ERR_FLAG) {
        f->flags = HSTPFD_FRAME_ERR;
        f->id = cf->can_id & CAN_ERR_MASK;
    } else if (cf->can_id & CAN_EFF_FLAG) {
        f->flags = HSTPFD_FRAME_EXT;
        f->id = cf->can_id & CAN_EFF_MASK;
    } else {
        f->id = cf->can_id & CAN_SFF_MASK;
    }
    if (cf->can_id & CAN_RTR_FLAG) {
        f->flags |= HSTPFD_FRAME_RTR;
    }
    f->len = cf->can_dlc > 8u ? 8u : cf->can_dlc;
    if (!(f->flags & HSTPFD_FRAME_RTR)) {
        memcpy(f->data, cf->data, f->len);
    }
}

/* Reads what is queued. Returns 0, or the errno that ended the socket. */
static int drain(hstpfd_core_t *c)
{
    for (;;) {
        if (c->stop != NULL && *c->stop) {
            return 0; /* a flooded bus must not hold off SIGTERM */
        }
        struct can_frame cf;
        struct iovec iov;
        struct msghdr msg;
        struct cmsghdr *cm;
        char ctrl[CMSG_SPACE(sizeof(struct timeval))];
        int64_t t_us = -1;
        hstpfd_frame_t f;
        ssize_t n;

        iov.iov_base = &cf;
        iov.iov_len = sizeof cf;
        memset(&msg, 0, sizeof msg);
        msg.msg_iov = &iov;
        msg.msg_iovlen = 1;
        msg.msg_control = ctrl;
        msg.msg_controllen = sizeof ctrl;
        n = recvmsg(io.fd, &msg, 0);
        if (n < 0) {
            if (errno == EAGAIN || errno == EWOULDBLOCK) {
                return 0;
            }
            if (errno == EINTR) {
                return 0;
            }
            ++c->n.read_errors;
            return errno;
        }
        if ((size_t)n != sizeof cf) {
            ++c->n.read_errors; /* not a classic CAN frame */
            continue;
        }
        for (cm = CMSG_FIRSTHDR(&msg); cm != NULL; cm = CMSG_NXTHDR(&msg, cm)) {
            if (cm->cmsg_level == SOL_SOCKET && cm->cmsg_type == SO_TIMESTAMP) {
                struct timeval tv;
                memcpy(&tv, CMSG_DATA(cm), sizeof tv);
                t_us = (int64_t)tv.tv_sec * 1000000 + tv.tv_usec;
            }
        }
        if (t_us < 0) {
            t_us = now_realtime_us(); /* no kernel stamp: the same clock, read now */
        }
        to_frame(&cf, t_us, &f);
        hstpfd_core_frame(c, &f);
    }
}

int hstpfd_iface_send(void *ctx, const hstpfd_frame_t *f)
{
    struct can_frame cf;
    ssize_t n;
    (void)ctx;
    if (io.fd < 0) {
        return HSTPFD_SEND_OFFLINE;
    }
    memset(&cf, 0, sizeof cf);
    cf.can_id = (f->flags & HSTPFD_FRAME_EXT) ? ((f->id & CAN_EFF_MASK) | CAN_EFF_FLAG) : (f->id & CAN_SFF_MASK);
    cf.can_dlc = f->len > 8u ? 8u : f->len;
    memcpy(cf.data, f->data, cf.can_dlc);
    n = write(io.fd, &cf, sizeof cf);
    return n == (ssize_t)sizeof cf ? 0 : -1;
}

static int fatal_errno(int e)
{
    return e == EAFNOSUPPORT || e == EPROTONOSUPPORT || e == EPERM || e == EACCES;
}

static void close_io(void)
{
    if (io.fd >= 0) {
        (void)close(io.fd);
        io.fd = -1;
    }
}

int hstpfd_run_iface(hstpfd_core_t *c, const char *iface, volatile sig_atomic_t *stop, const char **end)
{
    const int64_t reopen_us = (int64_t)(c->cfg->reopen_s * 1e6 + 0.5);
    int64_t next_try = 0;
    int opened_once = 0, warned = 0;

    io.core = c;
    io.fd = -1;
    *end = HSTPFD_END_ERROR;
    while (!*stop) {
        struct pollfd pfd;
        int64_t due, wait_us;
        int rc, timeout_ms;

        if (io.fd < 0 && now_mono_us() >= next_try) {
            io.fd = open_iface(iface, c->cfg->rx_filter);
            if (io.fd >= 0) {
                if (opened_once) {
                    ++c->n.reopens;
                    fprintf(stderr, "hstpfd: %s: reopened\n", iface);
                }
                opened_once = 1;
                warned = 0;
            } else {
                const int e = errno;
                if (fatal_errno(e)) {
                    fprintf(stderr, "hstpfd: %s: cannot open a CAN socket: %s%s\n", iface, strerror(e),
                            e == EAFNOSUPPORT ? " (this kernel has no SocketCAN)" : "");
                    return -1;
                }
                if (!warned) {
                    fprintf(stderr, "hstpfd: %s: %s; retrying every %g s\n", iface, strerror(e), c->cfg->reopen_s);
                    warned = 1;
                }
                next_try = now_mono_us() + reopen_us;
            }
        }
        /* wait for a frame, the next idle tick or the next reopen attempt */
        wait_us = 1000000;
        due = hstpfd_core_idle_due(c, now_realtime_us());
        if (due >= 0 && due < wait_us) {
            wait_us = due;
        }
        if (io.fd < 0) {
            const int64_t r = next_try - now_mono_us();
            if (r < wait_us) {
                wait_us = r > 0 ? r : 0;
            }
        }
        timeout_ms = (int)((wait_us + 999) / 1000);
        pfd.fd = io.fd;
        pfd.events = POLLIN;
        pfd.revents = 0;
        rc = poll(&pfd, io.fd >= 0 ? 1u : 0u, timeout_ms);
        if (rc < 0) {
            if (errno == EINTR) {
                continue;
            }
            fprintf(stderr, "hstpfd: poll: %s\n", strerror(errno));
            return -1;
        }
        if (rc == 0) {
            /* nothing was queued when poll returned, but a daemon held off the
             * CPU since may have frames queued now, stamped before this
             * moment: those first, so that time never runs past a queued
             * frame (it made the backlog late: issue 12, docs/vm.md) */
            const int64_t now = now_realtime_us();
            if (io.fd >= 0) {
                pfd.revents = 0;
                if (poll(&pfd, 1u, 0) > 0) {
                    continue;
                }
            }
            hstpfd_core_idle(c, now);
            continue;
        }
        if (pfd.revents & (POLLIN | POLLERR | POLLHUP | POLLNVAL)) {
            int e = drain(c);
            if (e == 0 && (pfd.revents & (POLLERR | POLLHUP | POLLNVAL))) {
                int se = 0;
                socklen_t len = (socklen_t)sizeof se;
                if (getsockopt(io.fd, SOL_SOCKET, SO_ERROR, &se, &len) == 0) {
                    e = se;
                }
                if (e == 0 && (pfd.revents & POLLNVAL)) {
                    e = EBADF;
                }
            }
            if (e != 0) {
                fprintf(stderr, "hstpfd: %s: %s; closing, reopening every %g s\n", iface, strerror(e),
                        c->cfg->reopen_s);
                close_io();
                warned = 1;
                next_try = now_mono_us() + reopen_us;
            }
        }
    }
    close_io();
    *end = HSTPFD_END_SIGNAL;
    return 0;
}
