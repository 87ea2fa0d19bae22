/*
 * fdi_can_play.c - play a candump log (.log, as written by python-can or candump -l) onto a SocketCAN interface.
 *
 *   fdi-can-play IFACE FILE.log [--speed X]
 *
 * Frames are sent at their log times (relative to the first frame) scaled by 1/X (default X = 1, real time;
 * X = 0 sends as fast as possible), timed with clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME). Malformed lines
 * are counted and skipped. Prints sent=, skipped=, late_max_us= (largest delay behind schedule) on stdout.
 * A small stand-in for can-utils' canplayer in the QEMU guest of tests/vm (built statically there).
 */
#define _GNU_SOURCE

#include <errno.h>
#include <inttypes.h>
#include <net/if.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include <linux/can.h>
#include <linux/can/raw.h>

static uint64_t now_ns(void)
{
    struct timespec ts;
    (void)clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * 1000000000U + (uint64_t)ts.tv_nsec;
}

static int hexval(char c)
{
    int v = -1;
    if ((c >= '0') && (c <= '9'))
    {
        v = c - '0';
    }
    else if ((c >= 'A') && (c <= 'F'))
    {
        v = c - 'A' + 10;
    }
    else if ((c >= 'a') && (c <= 'f'))
    {
        v = c - 'a' + 10;
    }
    return v;
}

/* "(T) CHANNEL ID#DATA [flags]" -> t, frame; 0 on success. */
static int parse_line(const char *line, double *t, struct can_frame *f)
{
    char chan[64];
    char tok[64];
    const char *hash;
    size_t id_len;
    size_t k;
    uint32_t id = 0U;
    const char *p;
    if (sscanf(line, " (%lf) %63s %63s", t, chan, tok) != 3)
    {
        return -1;
    }
    hash = strchr(tok, '#');
    if ((hash == NULL) || (hash == tok))
    {
        return -1;
    }
    id_len = (size_t)(hash - tok);
    if (id_len > 8U)
    {
        return -1;
    }
    for (k = 0U; k < id_len; ++k)
    {
        const int v = hexval(tok[k]);
        if (v < 0)
        {
            return -1;
        }
        id = (id << 4) | (uint32_t)v;
    }
    memset(f, 0, sizeof *f);
    f->can_id = (id_len > 3U) ? ((id & CAN_EFF_MASK) | CAN_EFF_FLAG) : id;
    p = hash + 1;
    if (*p == 'R')
    {
        f->can_id |= CAN_RTR_FLAG;
        return 0;
    }
    for (k = 0U; (p[0] != '\0') && (p[1] != '\0'); p += 2)
    {
        const int hi = hexval(p[0]);
        const int lo = hexval(p[1]);
        if ((hi < 0) || (lo < 0) || (k >= CAN_MAX_DLEN))
        {
            return -1;
        }
        f->data[k++] = (uint8_t)((hi << 4) | lo);
    }
    if (p[0] != '\0')
    {
        return -1;
    }
    f->can_dlc = (uint8_t)k;
    return 0;
}

int main(int argc, char **argv)
{
    double speed = 1.0;
    FILE *in;
    char line[512];
    int sock;
    struct sockaddr_can addr;
    uint64_t t0_ns = 0U;
    double t_first = 0.0;
    int have_first = 0;
    uint64_t sent = 0U;
    uint64_t skipped = 0U;
    uint64_t send_errors = 0U;
    uint64_t late_max_ns = 0U;
    if ((argc != 3) && !((argc == 5) && (strcmp(argv[3], "--speed") == 0)))
    {
        fprintf(stderr, "usage: %s IFACE FILE.log [--speed X]   (X = 0: as fast as possible)\n"
                        "  example: %s vcan0 drive.log --speed 1\n", argv[0], argv[0]);
        return 2;
    }
    if (argc == 5)
    {
        char *end = NULL;
        speed = strtod(argv[4], &end);
        if ((end == argv[4]) || (*end != '\0') || !(speed >= 0.0))
        {
            fprintf(stderr, "fdi-can-play: bad speed '%s'\n", argv[4]);
            return 2;
        }
    }
    in = fopen(argv[2], "r");
    if (in == NULL)
    {
        fprintf(stderr, "fdi-can-play: %s: %s\n", argv[2], strerror(errno));
        return 1;
    }
    sock = socket(PF_CAN, SOCK_RAW, CAN_RAW);
    memset(&addr, 0, sizeof addr);
    addr.can_family = AF_CAN;
    addr.can_ifindex = (int)if_nametoindex(argv[1]);
    if ((sock < 0) || (addr.can_ifindex == 0) || (bind(sock, (struct sockaddr *)&addr, sizeof addr) != 0))
    {
        fprintf(stderr, "fdi-can-play: cannot open %s: %s\n", argv[1], strerror(errno));
        (void)fclose(in);
        return 1;
    }
    while (fgets(line, (int)sizeof line, in) != NULL)
    {
        double t;
        struct can_frame f;
        if (parse_line(line, &t, &f) != 0)
        {
            skipped++;
            continue;
        }
        if (!have_first)
        {
            have_first = 1;
            t_first = t;
            t0_ns = now_ns();
        }
        if (speed > 0.0)
        {
            const double rel = (t - t_first) / speed;
            const uint64_t due = t0_ns + (uint64_t)((rel > 0.0 ? rel : 0.0) * 1e9);
            const uint64_t now = now_ns();
            if (due > now)
            {
                struct timespec ts;
                ts.tv_sec = (time_t)(due / 1000000000U);
                ts.tv_nsec = (long)(due % 1000000000U);
                while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, NULL) == EINTR)
                {
                }
            }
            else if (now - due > late_max_ns)
            {
                late_max_ns = now - due;
            }
        }
        for (;;)
        {
            if (write(sock, &f, sizeof f) == (ssize_t)sizeof f)
            {
                sent++;
                break;
            }
            if (errno != ENOBUFS)
            {
                send_errors++;
                break;
            }
            (void)usleep(100U); /* transmit queue full: wait for the bus */
        }
    }
    printf("sent=%" PRIu64 "\nskipped=%" PRIu64 "\nsend_errors=%" PRIu64 "\nlate_max_us=%" PRIu64 "\n", sent, skipped,
           send_errors, late_max_ns / 1000U);
    (void)fclose(in);
    (void)close(sock);
    return (send_errors == 0U) ? 0 : 1;
}
