/* A lean poller for benchmarks/scale.py: the harness must cost far less than what it measures.
 *
 *   poller RATE SECONDS MOVE OUT PORT...
 *
 * Connects to 127.0.0.1:PORT for every PORT (non-blocking sockets, one epoll), optionally sends
 * the SERS move command to each and drops the answers for 0.5 s (MOVE = 1), then polls every
 * device with "#P11?\r" at RATE Hz for SECONDS, each device at its own phase in the period
 * (device i of n is due at start + k / RATE + i / (n * RATE)), as scale.py's Python poller does.
 *
 * The process wakes once per millisecond at most (clock_nanosleep to the next due poll, rounded
 * up to the millisecond): it reads every answer that arrived (epoll_wait with a zero timeout),
 * then sends the polls now due, in one batch.  It never sleeps in epoll_wait, so an answer does
 * not wake it: with 40,000 answers a second, a wake-up per answer (an inter-processor interrupt
 * in a VM) would cost the poller and the answering process more than the rest of a poll.
 * A round trip is therefore timed by the kernel: from the clock just before the poll's write to
 * the receive timestamp of the answer's last segment (SO_TIMESTAMPNS, CLOCK_REALTIME on both).
 *
 * An answer is complete when the bytes since the last complete answer hold "\nok" followed later
 * by "\r" (with no later "\nok" still open), as checked at the end of each read: the Python
 * poller's rfind(b"\nok") and find(b"\r") on its buffer, done as a small state machine here.  A
 * poll is missed when the previous poll of the device has no complete answer when it is due
 * (the answers that arrived by then are read first).
 *
 * Prints "polling" when the polls begin (after the move and its answers), writes the round trips
 * (seconds, native float64) to OUT, and prints one JSON line:
 *   {"samples": n, "missed": n, "polls": n, "cpu": seconds, "wall": seconds}
 * where cpu is this process's user + system time over the measurement and wall its length.
 */
#define _GNU_SOURCE
#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/epoll.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

static const char QUERY[] = "#P11?\r";
static const char MOVE[] = "#ON V=30 WR=200000 E\r";

struct conn {
    int fd;
    int match;       /* how much of "\nok" the last bytes match (0..2) */
    int acked;       /* "\nok" seen since the last complete answer, and no "\r" after it yet */
    int complete;    /* "\nok" then "\r" seen, no "\nok" opened since */
    double sent_at;  /* < 0: no poll outstanding */
};

static double seconds_of(struct timespec ts) {
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

static double now(void) {  /* for the schedule */
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return seconds_of(ts);
}

static double wall_now(void) {  /* the clock of the kernel's receive timestamps */
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    return seconds_of(ts);
}

static void sleep_until(double when) {
    struct timespec ts = {.tv_sec = (time_t)when, .tv_nsec = (long)((when - (double)(time_t)when) * 1e9)};
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, NULL) == EINTR) {
    }
}

static double cpu_seconds(void) {
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    return (double)(ru.ru_utime.tv_sec + ru.ru_stime.tv_sec) + (double)(ru.ru_utime.tv_usec + ru.ru_stime.tv_usec) * 1e-6;
}

static void die(const char *what) {
    perror(what);
    exit(2);
}

static double *rtts;
static size_t n_rtts, cap_rtts;

static void record(double rtt) {
    if (n_rtts == cap_rtts) {
        cap_rtts = cap_rtts ? 2 * cap_rtts : 65536;
        rtts = realloc(rtts, cap_rtts * sizeof *rtts);
        if (!rtts) die("realloc");
    }
    rtts[n_rtts++] = rtt;
}

/* Feeds one read's bytes to c's state machine; returns 1 when an answer is complete. */
static int scan(struct conn *c, const char *data, ssize_t len) {
    for (ssize_t i = 0; i < len; i++) {
        char ch = data[i];
        if (c->match == 2 && ch == 'k') {
            c->acked = 1;
            c->complete = 0;
            c->match = 0;
            continue;
        }
        if (ch == '\r' && c->acked) c->complete = 1;
        c->match = ch == '\n' ? 1 : (c->match == 1 && ch == 'o') ? 2 : 0;
    }
    return c->complete;
}

static void reset(struct conn *c) {
    c->match = c->acked = c->complete = 0;
}

/* Reads what c has; with measuring, a complete answer ends the outstanding poll. */
static void on_readable(struct conn *c, int measuring) {
    char buf[4096];
    union {
        char space[CMSG_SPACE(sizeof(struct timespec))];
        struct cmsghdr align;
    } control;
    for (;;) {
        struct iovec iov = {.iov_base = buf, .iov_len = sizeof buf};
        struct msghdr msg = {.msg_iov = &iov, .msg_iovlen = 1, .msg_control = control.space,
                             .msg_controllen = sizeof control.space};
        ssize_t got = recvmsg(c->fd, &msg, 0);
        if (got > 0) {
            if (measuring && scan(c, buf, got)) {
                if (c->sent_at >= 0) {
                    struct cmsghdr *cm = CMSG_FIRSTHDR(&msg);
                    struct timespec ts;
                    if (!cm || cm->cmsg_level != SOL_SOCKET || cm->cmsg_type != SCM_TIMESTAMPNS) {
                        fprintf(stderr, "poller: no receive timestamp\n");
                        exit(2);
                    }
                    memcpy(&ts, CMSG_DATA(cm), sizeof ts);
                    record(seconds_of(ts) - c->sent_at);
                }
                c->sent_at = -1;
                reset(c);
            }
            if ((size_t)got < sizeof buf) return;
            continue;
        }
        if (got == 0) {
            fprintf(stderr, "poller: connection closed by the device\n");
            exit(2);
        }
        if (errno == EINTR) continue;
        if (errno == EAGAIN || errno == EWOULDBLOCK) return;
        die("recvmsg");
    }
}

static void send_all(int fd, const char *data, size_t len) {
    while (len) {
        ssize_t put = write(fd, data, len);
        if (put < 0) {
            if (errno == EINTR) continue;
            die("write");  /* a few bytes on an idle socket: the send buffer is never full */
        }
        data += put;
        len -= (size_t)put;
    }
}

/* Reads every answer that has arrived, without waiting. */
static void harvest(int ep, struct conn *conns, int measuring) {
    struct epoll_event events[256];
    int ready;
    do {
        ready = epoll_wait(ep, events, 256, 0);
        if (ready < 0 && errno != EINTR) die("epoll_wait");
        for (int i = 0; i < ready; i++) on_readable(&conns[events[i].data.u32], measuring);
    } while (ready == 256);
}

/* Reads the answers for `seconds`, once a millisecond. */
static void harvest_for(int ep, struct conn *conns, double seconds, int measuring) {
    for (double t = now(), until = t + seconds; t < until; t += 1e-3) {
        sleep_until(t);
        harvest(ep, conns, measuring);
    }
}

int main(int argc, char **argv) {
    if (argc < 6) {
        fprintf(stderr, "usage: poller RATE SECONDS MOVE OUT PORT...\n");
        return 2;
    }
    double rate = atof(argv[1]), seconds = atof(argv[2]);
    int move = atoi(argv[3]);
    const char *out = argv[4];
    int n = argc - 5;

    struct rlimit lim;  /* a socket per device */
    if (getrlimit(RLIMIT_NOFILE, &lim) == 0 && lim.rlim_cur < lim.rlim_max) {
        lim.rlim_cur = lim.rlim_max;
        setrlimit(RLIMIT_NOFILE, &lim);
    }
    int ep = epoll_create1(0);
    if (ep < 0) die("epoll_create1");
    struct conn *conns = calloc((size_t)n, sizeof *conns);
    if (!conns) die("calloc");
    for (int i = 0; i < n; i++) {
        struct sockaddr_in addr = {.sin_family = AF_INET, .sin_port = htons((uint16_t)atoi(argv[5 + i]))};
        addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
        int fd = socket(AF_INET, SOCK_STREAM, 0);
        if (fd < 0) die("socket");
        if (connect(fd, (struct sockaddr *)&addr, sizeof addr) < 0) die("connect");  /* loopback: at once */
        int one = 1;
        setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
        if (setsockopt(fd, SOL_SOCKET, SO_TIMESTAMPNS, &one, sizeof one) < 0) die("SO_TIMESTAMPNS");
        fcntl(fd, F_SETFL, fcntl(fd, F_GETFL) | O_NONBLOCK);
        conns[i] = (struct conn){.fd = fd, .sent_at = -1};
        struct epoll_event ev = {.events = EPOLLIN, .data.u32 = (uint32_t)i};
        if (epoll_ctl(ep, EPOLL_CTL_ADD, fd, &ev) < 0) die("epoll_ctl");
    }
    if (move) {
        for (int i = 0; i < n; i++) send_all(conns[i].fd, MOVE, sizeof MOVE - 1);
        harvest_for(ep, conns, 0.5, 0);  /* the move's answers are read and dropped */
    }

    double step = 1.0 / (rate * n), start = now() + 0.2;
    long total = (long)(seconds * rate) * n, next = 0, missed = 0;
    harvest_for(ep, conns, 0.2, 0);
    puts("polling");  /* the conductor starts its CPU accounts here */
    fflush(stdout);
    double cpu0 = cpu_seconds(), wall0 = now();
    while (next < total) {
        double ms = (double)next * step * 1e3;  /* the polls due in this millisecond go in one batch */
        sleep_until(start + (double)((long)ms + ((double)(long)ms < ms)) * 1e-3);
        harvest(ep, conns, 1);
        for (double t = now(); next < total && start + (double)next * step <= t; next++) {
            struct conn *c = &conns[next % n];
            if (c->sent_at >= 0) {
                missed++;  /* the last answer is not in yet: this poll is missed */
                continue;
            }
            c->sent_at = wall_now();
            send_all(c->fd, QUERY, sizeof QUERY - 1);
        }
    }
    harvest_for(ep, conns, 0.2, 1);
    double cpu = cpu_seconds() - cpu0, wall = now() - wall0;

    FILE *fh = fopen(out, "wb");
    if (!fh || fwrite(rtts, sizeof *rtts, n_rtts, fh) != n_rtts || fclose(fh)) die(out);
    printf("{\"samples\": %zu, \"missed\": %ld, \"polls\": %ld, \"cpu\": %.3f, \"wall\": %.3f}\n", n_rtts, missed,
           total, cpu, wall);
    return 0;
}
