/* The floor under the closed loop: two processes answering each other over a
 * pseudo-terminal as the simulator and the runtime do, with nothing else to do. The
 * parent writes a SENSORS-sized frame to the master and waits (poll) for a
 * COMMAND-sized answer; the child, on the raw slave, waits for the frame and answers.
 *
 *     pty_roundtrip N SENSORS_BYTES COMMAND_BYTES
 *
 * prints "ROUND_TRIPS WALL_S CPU_S": N round trips, their wall time and the CPU time
 * (user + system) of both processes. */
#define _XOPEN_SOURCE 700
#include <fcntl.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

static double now_s(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + (double)t.tv_nsec * 1e-9;
}

static double cpu_s(int who)
{
    struct rusage r;
    getrusage(who, &r);
    return (double)(r.ru_utime.tv_sec + r.ru_stime.tv_sec)
        + (double)(r.ru_utime.tv_usec + r.ru_stime.tv_usec) * 1e-6;
}

static void make_raw(int fd)
{
    struct termios t;
    tcgetattr(fd, &t);
    t.c_iflag = 0;
    t.c_oflag = 0;
    t.c_lflag = 0;
    t.c_cflag = CS8 | CREAD | CLOCAL;
    t.c_cc[VMIN] = 1;
    t.c_cc[VTIME] = 0;
    tcsetattr(fd, TCSANOW, &t);
}

/* Wait for and read `n` bytes, as the two sides do: poll, then read what is there. */
static int take(int fd, char *buf, int n)
{
    for (int got = 0; got < n;) {
        struct pollfd p = {fd, POLLIN, 0};
        if (poll(&p, 1, 10000) != 1) {
            return -1;
        }
        ssize_t r = read(fd, buf + got, (size_t)(n - got));
        if (r <= 0) {
            return -1;
        }
        got += (int)r;
    }
    return 0;
}

int main(int argc, char **argv)
{
    if (argc != 4) {
        fprintf(stderr, "usage: pty_roundtrip N SENSORS_BYTES COMMAND_BYTES\n");
        return 2;
    }
    int n = atoi(argv[1]), out = atoi(argv[2]), back = atoi(argv[3]);
    char buf[256] = {1};
    if (n < 1 || out < 1 || back < 1 || out > 256 || back > 256) {
        return 2;
    }
    int master = posix_openpt(O_RDWR | O_NOCTTY);
    if (master < 0 || grantpt(master) < 0 || unlockpt(master) < 0) {
        perror("pty");
        return 1;
    }
    make_raw(master);
    const char *name = ptsname(master);
    pid_t child = fork();
    if (child == 0) {
        int slave = open(name, O_RDWR | O_NOCTTY);
        make_raw(slave);
        write(slave, buf, 1);  /* ready */
        for (int i = 0; i < n; i++) {
            if (take(slave, buf, out) < 0 || write(slave, buf, (size_t)back) != back) {
                _exit(1);
            }
        }
        _exit(0);
    }
    if (take(master, buf, 1) < 0) {
        return 1;
    }
    double start = now_s(), cpu = cpu_s(RUSAGE_SELF);
    for (int i = 0; i < n; i++) {
        if (write(master, buf, (size_t)out) != out || take(master, buf, back) < 0) {
            return 1;
        }
    }
    double wall = now_s() - start;
    int status;
    waitpid(child, &status, 0);
    cpu = cpu_s(RUSAGE_SELF) - cpu + cpu_s(RUSAGE_CHILDREN);
    printf("%d %.6f %.6f\n", n, wall, cpu);
    return WIFEXITED(status) && WEXITSTATUS(status) == 0 ? 0 : 1;
}
