/* hstpfd-cantool: the two bus ends of the vcan test (Linux SocketCAN).
 *   hstpfd-cantool play IFACE LOG [SPEEDUP]  sends a candump log's frames
 *       with the log's timing divided by SPEEDUP (default 1)
 *   hstpfd-cantool dump IFACE SECONDS        writes what it receives for
 *       SECONDS as a candump log to stdout (kernel timestamps)
 * Error frames in a log are skipped by play (a vcan cannot send them). */
#define _DEFAULT_SOURCE 1

#include <errno.h>
#include <net/if.h>
#include <poll.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <time.h>
#include <unistd.h>

#include <linux/can.h>
#include <linux/can/raw.h>

#include "candump.h"

static int open_bound(const char *ifname)
{
    struct sockaddr_can addr;
    struct ifreq ifr;
    const int on = 1;
    int s = socket(PF_CAN, SOCK_RAW, CAN_RAW);
    if (s < 0) {
        perror("cantool: socket");
        return -1;
    }
    memset(&ifr, 0, sizeof ifr);
    (void)snprintf(ifr.ifr_name, sizeof ifr.ifr_name, "%s", ifname);
    if (ioctl(s, SIOCGIFINDEX, &ifr) < 0) {
        perror("cantool: SIOCGIFINDEX");
        close(s);
        return -1;
    }
    memset(&addr, 0, sizeof addr);
    addr.can_family = AF_CAN;
    addr.can_ifindex = ifr.ifr_ifindex;
    (void)setsockopt(s, SOL_SOCKET, SO_TIMESTAMP, &on, sizeof on);
    if (bind(s, (struct sockaddr *)(void *)&addr, sizeof addr) < 0) {
        perror("cantool: bind");
        close(s);
        return -1;
    }
    return s;
}

static int64_t mono_us(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000000 + ts.tv_nsec / 1000;
}

static void sleep_until(int64_t t_us)
{
    for (;;) {
        const int64_t d = t_us - mono_us();
        struct timespec ts;
        if (d <= 0) {
            return;
        }
        ts.tv_sec = (time_t)(d / 1000000);
        ts.tv_nsec = (long)(d % 1000000) * 1000;
        (void)nanosleep(&ts, NULL);
    }
}

static int play(const char *ifname, const char *path, double speedup)
{
    FILE *fp = fopen(path, "r");
    char line[512];
    int s = open_bound(ifname);
    int64_t log0 = -1, wall0 = 0;
    unsigned long sent = 0, dropped = 0;
    if (fp == NULL || s < 0) {
        fprintf(stderr, "cantool: cannot open %s or %s\n", path, ifname);
        return 1;
    }
    while (fgets(line, sizeof line, fp) != NULL) {
        hstpfd_frame_t f;
        struct can_frame cf;
        if (hstpfd_candump_parse(line, &f, NULL, 0) != HSTPFD_CANDUMP_OK || (f.flags & HSTPFD_FRAME_ERR)) {
            continue;
        }
        if (log0 < 0) {
            log0 = f.t_us;
            wall0 = mono_us();
        }
        sleep_until(wall0 + (int64_t)((double)(f.t_us - log0) / speedup));
        memset(&cf, 0, sizeof cf);
        cf.can_id = (f.flags & HSTPFD_FRAME_EXT) ? (f.id | CAN_EFF_FLAG) : f.id;
        if (f.flags & HSTPFD_FRAME_RTR) {
            cf.can_id |= CAN_RTR_FLAG;
        }
        cf.can_dlc = f.len > 8 ? 8 : f.len;
        memcpy(cf.data, f.data, cf.can_dlc);
        for (;;) {
            if (write(s, &cf, sizeof cf) == (ssize_t)sizeof cf) {
                ++sent;
                break;
            }
            if (errno == ENOBUFS) { /* queue full: wait a little */
                usleep(200);
                continue;
            }
            ++dropped; /* e.g. the interface is down */
            break;
        }
    }
    fclose(fp);
    close(s);
    fprintf(stderr, "cantool: sent %lu frames, %lu not sent\n", sent, dropped);
    return 0;
}

static volatile sig_atomic_t stop;

static void on_signal(int sig)
{
    (void)sig;
    stop = 1;
}

static int dump(const char *ifname, double seconds)
{
    const int s = open_bound(ifname);
    const int64_t end = mono_us() + (int64_t)(seconds * 1e6);
    const int on = 1, rcvbuf = 4 << 20;
    unsigned long frames = 0;
    uint32_t overflows = 0;
    struct sigaction sa;
    if (s < 0) {
        return 1;
    }
    /* A dump that falls behind (a busy machine, an emulated VM) loses
     * frames in the kernel: a large queue, and its drop count reported. */
    if (setsockopt(s, SOL_SOCKET, SO_RCVBUFFORCE, &rcvbuf, sizeof rcvbuf) != 0) {
        (void)setsockopt(s, SOL_SOCKET, SO_RCVBUF, &rcvbuf, sizeof rcvbuf);
    }
    (void)setsockopt(s, SOL_SOCKET, SO_RXQ_OVFL, &on, sizeof on);
    /* ended by SIGTERM or SIGINT: stdout is flushed at the end, so it
     * needs no write per line */
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    (void)sigaction(SIGTERM, &sa, NULL);
    (void)sigaction(SIGINT, &sa, NULL);
    while (!stop) {
        struct pollfd p;
        const int64_t left = end - mono_us();
        if (left <= 0) {
            break;
        }
        p.fd = s;
        p.events = POLLIN;
        /* at most 100 ms, so that a signal just before poll ends it soon */
        if (poll(&p, 1, left > 100000 ? 100 : (int)(left / 1000) + 1) > 0) {
            struct can_frame cf;
            struct iovec iov = {&cf, sizeof cf};
            char ctrl[CMSG_SPACE(sizeof(struct timeval)) + CMSG_SPACE(sizeof(uint32_t))];
            struct msghdr msg;
            struct cmsghdr *cm;
            hstpfd_frame_t f;
            char line[256];
            memset(&msg, 0, sizeof msg);
            msg.msg_iov = &iov;
            msg.msg_iovlen = 1;
            msg.msg_control = ctrl;
            msg.msg_controllen = sizeof ctrl;
            if (recvmsg(s, &msg, 0) != (ssize_t)sizeof cf) {
                continue; /* e.g. ENETDOWN while the interface is down */
            }
            memset(&f, 0, sizeof f);
            for (cm = CMSG_FIRSTHDR(&msg); cm != NULL; cm = CMSG_NXTHDR(&msg, cm)) {
                if (cm->cmsg_level == SOL_SOCKET && cm->cmsg_type == SO_TIMESTAMP) {
                    struct timeval tv;
                    memcpy(&tv, CMSG_DATA(cm), sizeof tv);
                    f.t_us = (int64_t)tv.tv_sec * 1000000 + tv.tv_usec;
                } else if (cm->cmsg_level == SOL_SOCKET && cm->cmsg_type == SO_RXQ_OVFL) {
                    memcpy(&overflows, CMSG_DATA(cm), sizeof overflows);
                }
            }
            f.flags = (cf.can_id & CAN_EFF_FLAG) ? HSTPFD_FRAME_EXT : 0;
            f.id = cf.can_id & ((cf.can_id & CAN_EFF_FLAG) ? CAN_EFF_MASK : CAN_SFF_MASK);
            f.len = cf.can_dlc > 8 ? 8 : cf.can_dlc;
            memcpy(f.data, cf.data, f.len);
            if (hstpfd_candump_format(&f, ifname, line, sizeof line) > 0) {
                fputs(line, stdout);
                ++frames;
            }
        }
    }
    close(s);
    fflush(stdout);
    fprintf(stderr, "cantool: dumped %lu frames, %lu dropped by the kernel (receive queue full)\n", frames,
            (unsigned long)overflows);
    return 0;
}

int main(int argc, char **argv)
{
    if (argc >= 4 && strcmp(argv[1], "play") == 0) {
        return play(argv[2], argv[3], argc >= 5 ? atof(argv[4]) : 1.0);
    }
    if (argc == 4 && strcmp(argv[1], "dump") == 0) {
        return dump(argv[2], atof(argv[3]));
    }
    fprintf(stderr, "usage: hstpfd-cantool play IFACE LOG [SPEEDUP] | dump IFACE SECONDS\n");
    return 2;
}
