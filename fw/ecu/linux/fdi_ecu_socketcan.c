/*
 * fdi_ecu_socketcan.c - the ECU process on a Linux SocketCAN interface (can0 with a USB-CAN adapter, vcan0).
 *
 *   fdi-ecu-socketcan IFACE [--table kin|romo] [--quiet]
 *
 * Reads every classic CAN frame of IFACE with its receive time (CLOCK_MONOTONIC), hands it to fdi_ecu_rx()
 * and calls fdi_ecu_poll() after it; a timerfd fires 50 us after every diagnosis step boundary so that the
 * step also runs on a silent bus. Diagnosis frames (ID 512) are written to the same interface. SIGINT or
 * SIGTERM ends the loop; the counters and the last result are printed (key=value lines) on stdout.
 * Not part of the firmware library: built by CMake on Linux only (fw/ecu/linux/).
 */
#define _GNU_SOURCE /* timerfd, signals, if_nametoindex with -std=c99 */

#include <errno.h>
#include <inttypes.h>
#include <net/if.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/timerfd.h>
#include <time.h>
#include <unistd.h>

#include <linux/can.h>
#include <linux/can/raw.h>

#include "fdi_ecu.h"
#include "fdi_kin_table.h"
#include "fdi_romo_ecu.h"
#include "fdi_romo_table.h"

static volatile sig_atomic_t stop_requested = 0;

static void on_signal(int sig)
{
    (void)sig;
    stop_requested = 1;
}

static uint64_t now_us(void)
{
    struct timespec ts;
    (void)clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * 1000000U + (uint64_t)ts.tv_nsec / 1000U;
}

static int usage(const char *prog)
{
    fprintf(stderr,
            "usage: %s IFACE [--table kin|romo] [--quiet]\n"
            "  Runs the fault diagnosis ECU on SocketCAN interface IFACE (e.g. can0, vcan0): sensor frames in,\n"
            "  FDI_Diagnosis frames (ID 512) out every diagnosis step. Ctrl-C prints the counters.\n"
            "  example: %s vcan0 --table kin\n",
            prog, prog);
    return 2;
}

static const char *const reason_names[FDI_ECU_N_REASONS] = {
    "unknown_id", "own_frame", "bad_dlc", "bad_crc", "out_of_range", "repeated_counter", "counter_jump",
    "sensor_status"};

static void print_report(const fdi_ecu_t *ecu, uint64_t tx_errors)
{
    fdi_ecu_counters_t c;
    fdi_ecu_result_t r;
    uint32_t i;
    uint32_t k;
    if ((fdi_ecu_counters(ecu, &c) != FDI_OK) || (fdi_ecu_result(ecu, &r) != FDI_OK))
    {
        return;
    }
    printf("frames=%" PRIu32 "\n", c.frames);
    for (k = 0U; k < FDI_ECU_N_REASONS; ++k)
    {
        printf("rejected.%s=%" PRIu32 "\n", reason_names[k], c.rejected[k]);
    }
    for (i = 0U; i < (uint32_t)fdi_romo_bus.n_msgs; ++i)
    {
        printf("msg.0x%03" PRIX32 " received=%" PRIu32 " accepted=%" PRIu32 " timeouts=%" PRIu32 "\n",
               c.msg[i].can_id, c.msg[i].received, c.msg[i].accepted, c.msg[i].timeouts);
    }
    printf("steps=%" PRIu32 "\nsteps_skipped=%" PRIu32 "\ntx_frames=%" PRIu32 "\ntx_errors=%" PRIu64 "\n", c.steps,
           c.steps_skipped, c.tx_frames, tx_errors);
    printf("result.status=%u\nresult.alarm_mask=0x%" PRIX32 "\nresult.evaluable_mask=0x%" PRIX32
           "\nresult.candidates=0x%" PRIX32 "\nresult.iso_class=%u\n",
           (unsigned)r.status, r.diag.alarm_mask, r.diag.evaluable_mask, r.diag.iso.candidates,
           (unsigned)r.iso_class);
    (void)fflush(stdout);
}

static int send_tx(int sock, const fdi_ecu_tx_t *tx, uint64_t *tx_errors)
{
    uint8_t i;
    for (i = 0U; i < tx->n_frames; ++i)
    {
        struct can_frame f;
        memset(&f, 0, sizeof f);
        f.can_id = tx->frame[i].can_id;
        f.can_dlc = tx->frame[i].dlc;
        memcpy(f.data, tx->frame[i].data, tx->frame[i].dlc);
        if (write(sock, &f, sizeof f) != (ssize_t)sizeof f)
        {
            (*tx_errors)++; /* bus off, buffer full: counted, the next step sends again */
        }
    }
    return 0;
}

int main(int argc, char **argv)
{
    const char *iface = NULL;
    const fdi_table_t *table = &fdi_romo_table;
    int quiet = 0;
    int i;
    static fdi_ecu_t ecu; /* ~5 kB: static rather than on the stack */
    fdi_ecu_config_t cfg;
    int sock;
    int tfd;
    struct sockaddr_can addr;
    struct itimerspec its;
    struct sigaction sa;
    uint64_t tx_errors = 0U;
    uint64_t step_us;
    uint64_t t_start;

    for (i = 1; i < argc; ++i)
    {
        if ((strcmp(argv[i], "--table") == 0) && (i + 1 < argc))
        {
            ++i;
            if (strcmp(argv[i], "kin") == 0)
            {
                table = &fdi_kin_table;
            }
            else if (strcmp(argv[i], "romo") == 0)
            {
                table = &fdi_romo_table;
            }
            else
            {
                fprintf(stderr, "unknown table '%s' (kin or romo)\n", argv[i]);
                return 2;
            }
        }
        else if (strcmp(argv[i], "--quiet") == 0)
        {
            quiet = 1;
        }
        else if ((strcmp(argv[i], "-h") == 0) || (strcmp(argv[i], "--help") == 0))
        {
            (void)usage(argv[0]);
            return 0;
        }
        else if ((argv[i][0] != '-') && (iface == NULL))
        {
            iface = argv[i];
        }
        else
        {
            return usage(argv[0]);
        }
    }
    if ((iface == NULL) || (strlen(iface) >= IFNAMSIZ))
    {
        return usage(argv[0]);
    }
    if ((fdi_romo_ecu_config_default(&cfg, table) != FDI_OK) || (fdi_ecu_init(&ecu, &cfg) != FDI_OK))
    {
        fprintf(stderr, "fdi-ecu-socketcan: the diagnosis table is not valid\n");
        return 1;
    }

    sock = socket(PF_CAN, SOCK_RAW, CAN_RAW);
    if (sock < 0)
    {
        fprintf(stderr, "fdi-ecu-socketcan: socket(PF_CAN): %s (no SocketCAN in this kernel?)\n", strerror(errno));
        return 1;
    }
    memset(&addr, 0, sizeof addr);
    addr.can_family = AF_CAN;
    addr.can_ifindex = (int)if_nametoindex(iface);
    if (addr.can_ifindex == 0)
    {
        fprintf(stderr, "fdi-ecu-socketcan: no interface '%s'\n", iface);
        (void)close(sock);
        return 1;
    }
    if (bind(sock, (struct sockaddr *)&addr, sizeof addr) != 0)
    {
        fprintf(stderr, "fdi-ecu-socketcan: bind %s: %s\n", iface, strerror(errno));
        (void)close(sock);
        return 1;
    }

    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    (void)sigemptyset(&sa.sa_mask);
    (void)sigaction(SIGINT, &sa, NULL);
    (void)sigaction(SIGTERM, &sa, NULL);

    /* timer 50 us after every step boundary of the core's schedule (which starts at the first call below) */
    step_us = (uint64_t)(table->design.dt * 1.0e6f + 0.5f);
    tfd = timerfd_create(CLOCK_MONOTONIC, TFD_NONBLOCK);
    if (tfd < 0)
    {
        fprintf(stderr, "fdi-ecu-socketcan: timerfd: %s\n", strerror(errno));
        (void)close(sock);
        return 1;
    }
    t_start = now_us();
    {
        fdi_ecu_tx_t tx;
        const uint64_t first = t_start + step_us + 50U;
        (void)fdi_ecu_poll(&ecu, (uint32_t)t_start, &tx); /* starts the step clock at t_start */
        memset(&its, 0, sizeof its);
        its.it_value.tv_sec = (time_t)(first / 1000000U);
        its.it_value.tv_nsec = (long)((first % 1000000U) * 1000U);
        its.it_interval.tv_sec = (time_t)(step_us / 1000000U);
        its.it_interval.tv_nsec = (long)((step_us % 1000000U) * 1000U);
        (void)timerfd_settime(tfd, TFD_TIMER_ABSTIME, &its, NULL);
    }
    if (!quiet)
    {
        fprintf(stderr, "fdi-ecu-socketcan: %s, table with %u tests, step %" PRIu64 " us; Ctrl-C to stop\n", iface,
                (unsigned)table->n_tests, step_us);
    }

    while (stop_requested == 0)
    {
        struct pollfd pfd[2];
        pfd[0].fd = sock;
        pfd[0].events = POLLIN;
        pfd[0].revents = 0;
        pfd[1].fd = tfd;
        pfd[1].events = POLLIN;
        pfd[1].revents = 0;
        if (poll(pfd, 2, 1000) < 0)
        {
            if (errno == EINTR)
            {
                continue;
            }
            fprintf(stderr, "fdi-ecu-socketcan: poll: %s\n", strerror(errno));
            break;
        }
        if ((pfd[0].revents & POLLIN) != 0)
        {
            struct can_frame f;
            const ssize_t n = read(sock, &f, sizeof f);
            if (n == (ssize_t)sizeof f)
            {
                const uint32_t t = (uint32_t)now_us();
                fdi_ecu_tx_t tx;
                const uint8_t dlc = (f.can_dlc <= CAN_MAX_DLEN) ? f.can_dlc : (uint8_t)0xFFU;
                /* the raw can_id keeps the EFF/RTR/ERR flags: such frames are counted as unknown IDs */
                (void)fdi_ecu_rx(&ecu, f.can_id, dlc, f.data, t);
                (void)fdi_ecu_poll(&ecu, t, &tx);
                (void)send_tx(sock, &tx, &tx_errors);
            }
        }
        if ((pfd[1].revents & POLLIN) != 0)
        {
            uint64_t expirations;
            fdi_ecu_tx_t tx;
            (void)read(tfd, &expirations, sizeof expirations);
            (void)fdi_ecu_poll(&ecu, (uint32_t)now_us(), &tx);
            (void)send_tx(sock, &tx, &tx_errors);
        }
    }
    print_report(&ecu, tx_errors);
    (void)close(tfd);
    (void)close(sock);
    return 0;
}
