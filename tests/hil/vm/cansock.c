/* Smoke test for tests/hil/vm: two raw AF_CAN sockets on one interface,
 * one sends a frame, the other must receive it unchanged.
 * Usage: cansock [IFACE]   (default vcan0). Exit 0 on success. */
#define _DEFAULT_SOURCE
#include <linux/can.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <poll.h>
#include <stdio.h>
#include <string.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

static int open_bound(const char *ifname)
{
    struct sockaddr_can addr;
    struct ifreq ifr;
    int s = socket(PF_CAN, SOCK_RAW, CAN_RAW);

    if (s < 0) {
        perror("cansock: socket(PF_CAN)");
        return -1;
    }
    memset(&ifr, 0, sizeof ifr);
    strncpy(ifr.ifr_name, ifname, IFNAMSIZ - 1);
    if (ioctl(s, SIOCGIFINDEX, &ifr) < 0) {
        perror("cansock: SIOCGIFINDEX");
        close(s);
        return -1;
    }
    memset(&addr, 0, sizeof addr);
    addr.can_family = AF_CAN;
    addr.can_ifindex = ifr.ifr_ifindex;
    if (bind(s, (struct sockaddr *)&addr, sizeof addr) < 0) {
        perror("cansock: bind");
        close(s);
        return -1;
    }
    return s;
}

int main(int argc, char **argv)
{
    const char *ifname = argc > 1 ? argv[1] : "vcan0";
    struct can_frame tx, rx;
    struct pollfd pfd;
    int a = open_bound(ifname);
    int b = open_bound(ifname);

    if (a < 0 || b < 0)
        return 1;
    memset(&tx, 0, sizeof tx);
    tx.can_id = 0x1A5;
    tx.can_dlc = 4;
    memcpy(tx.data, "\xde\xad\xbe\xef", 4);
    if (write(a, &tx, sizeof tx) != (ssize_t)sizeof tx) {
        perror("cansock: write");
        return 1;
    }
    pfd.fd = b;
    pfd.events = POLLIN;
    if (poll(&pfd, 1, 2000) != 1 || read(b, &rx, sizeof rx) != (ssize_t)sizeof rx) {
        fprintf(stderr, "cansock: no frame received on %s\n", ifname);
        return 1;
    }
    if (rx.can_id != tx.can_id || rx.can_dlc != tx.can_dlc || memcmp(rx.data, tx.data, 4) != 0) {
        fprintf(stderr, "cansock: received a different frame\n");
        return 1;
    }
    printf("cansock: C AF_CAN raw sockets exchanged 0x%03X [%d] on %s\n", (unsigned)rx.can_id,
           rx.can_dlc, ifname);
    close(a);
    close(b);
    return 0;
}
