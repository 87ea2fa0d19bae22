/*
 * fdi_can_record.c - record the frames of a SocketCAN interface to a candump log until SIGINT/SIGTERM.
 *
 *   fdi-can-record IFACE OUT.log [--id ID]
 *
 * One line per frame, "(seconds) IFACE ID#DATA" with the CLOCK_MONOTONIC receive time (the format python-can
 * and can-utils read). --id keeps only one (hexadecimal) standard ID, e.g. --id 200 for the diagnosis frames.
 * Prints frames= on stdout at the end. A stand-in for candump in the QEMU guest of tests/vm.
 */
#define _GNU_SOURCE

#include <errno.h>
#include <inttypes.h>
#include <net/if.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include <linux/can.h>
#include <linux/can/raw.h>

static volatile sig_atomic_t stop_requested = 0;

static void on_signal(int sig)
{
    (void)sig;
    stop_requested = 1;
}

int main(int argc, char **argv)
{
    long only_id = -1;
    FILE *out;
    int sock;
    struct sockaddr_can addr;
    struct sigaction sa;
    uint64_t frames = 0U;
    if ((argc != 3) && !((argc == 5) && (strcmp(argv[3], "--id") == 0)))
    {
        fprintf(stderr, "usage: %s IFACE OUT.log [--id HEXID]\n  example: %s vcan0 diag.log --id 200\n", argv[0],
                argv[0]);
        return 2;
    }
    if (argc == 5)
    {
        char *end = NULL;
        only_id = strtol(argv[4], &end, 16);
        if ((end == argv[4]) || (*end != '\0') || (only_id < 0) || (only_id > 0x7FF))
        {
            fprintf(stderr, "fdi-can-record: bad id '%s'\n", argv[4]);
            return 2;
        }
    }
    sock = socket(PF_CAN, SOCK_RAW, CAN_RAW);
    memset(&addr, 0, sizeof addr);
    addr.can_family = AF_CAN;
    addr.can_ifindex = (int)if_nametoindex(argv[1]);
    if ((sock < 0) || (addr.can_ifindex == 0) || (bind(sock, (struct sockaddr *)&addr, sizeof addr) != 0))
    {
        fprintf(stderr, "fdi-can-record: cannot open %s: %s\n", argv[1], strerror(errno));
        return 1;
    }
    out = fopen(argv[2], "w");
    if (out == NULL)
    {
        fprintf(stderr, "fdi-can-record: %s: %s\n", argv[2], strerror(errno));
        (void)close(sock);
        return 1;
    }
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    (void)sigemptyset(&sa.sa_mask);
    (void)sigaction(SIGINT, &sa, NULL);
    (void)sigaction(SIGTERM, &sa, NULL);
    while (stop_requested == 0)
    {
        struct pollfd pfd;
        struct can_frame f;
        struct timespec ts;
        int k;
        pfd.fd = sock;
        pfd.events = POLLIN;
        pfd.revents = 0;
        if ((poll(&pfd, 1, 200) <= 0) || (read(sock, &f, sizeof f) != (ssize_t)sizeof f))
        {
            continue;
        }
        (void)clock_gettime(CLOCK_MONOTONIC, &ts);
        if ((only_id >= 0) && (f.can_id != (canid_t)only_id))
        {
            continue;
        }
        if ((f.can_id & CAN_EFF_FLAG) != 0U)
        {
            fprintf(out, "(%lld.%06ld) %s %08" PRIX32 "#", (long long)ts.tv_sec, ts.tv_nsec / 1000L, argv[1],
                    (uint32_t)(f.can_id & CAN_EFF_MASK));
        }
        else
        {
            fprintf(out, "(%lld.%06ld) %s %03" PRIX32 "#", (long long)ts.tv_sec, ts.tv_nsec / 1000L, argv[1],
                    (uint32_t)(f.can_id & CAN_SFF_MASK));
        }
        for (k = 0; k < (int)f.can_dlc && k < CAN_MAX_DLEN; ++k)
        {
            fprintf(out, "%02X", f.data[k]);
        }
        fputc('\n', out);
        frames++;
    }
    (void)fclose(out);
    printf("frames=%" PRIu64 "\n", frames);
    (void)close(sock);
    return 0;
}
