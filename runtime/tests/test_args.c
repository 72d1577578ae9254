/* The runtime's command line: defaults, every option, and clear refusals. */
#include "gp_link.h"
#include "gp_test.h"

static int parse(int argc, const char *const *argv, gp_args *args, char *error)
{
    return gp_args_parse(argc, (char **)argv, args, error, 256);
}

void test_args_should_parse_every_option(void)
{
    const char *argv[] = {"prog", "--device", "/dev/ttyS1", "--plan", "p.plan", "--state-dir",
                          "st", "--link-timeout-s", "2.5", "--retransmit-ms", "50",
                          "--naive-tracker", "--clock-file", "speed", "--suspend-file",
                          "state", "--key", "k.key"};
    gp_args args;
    char error[256];
    CHECK_INT(parse(18, argv, &args, error), 0);
    CHECK(strcmp(args.clock_path, "speed") == 0);
    CHECK(strcmp(args.key_path, "k.key") == 0);
    CHECK(strcmp(args.suspend_path, "state") == 0);
    CHECK(strcmp(args.device, "/dev/ttyS1") == 0);
    CHECK(strcmp(args.plan_path, "p.plan") == 0);
    CHECK(strcmp(args.state_dir, "st") == 0);
    CHECK_NEAR(args.link_timeout_s, 2.5, 0);
    CHECK_INT(args.retransmit_ms, 50);
    CHECK_INT(args.naive_tracker, 1);
    CHECK_INT(parse(3, argv, &args, error), 0);
    CHECK(args.plan_path == NULL && args.state_dir == NULL && args.clock_path == NULL
          && args.suspend_path == NULL && args.key_path == NULL);
    CHECK_NEAR(args.link_timeout_s, GP_LINK_TIMEOUT_S, 0);
    CHECK_INT(args.retransmit_ms, GP_RETRANSMIT_MS);
    CHECK_INT(args.naive_tracker, 0);
}

void test_args_should_refuse_bad_command_lines(void)
{
    static const struct {
        int argc;
        const char *argv[4];
        const char *message;
    } rows[] = {
        {1, {"prog"}, "--device is required"},
        {2, {"prog", "--device"}, "--device needs a value"},
        {3, {"prog", "--devise", "x"}, "unknown argument '--devise'"},
        {4, {"prog", "--device", "x", "--retransmit-ms"}, "--retransmit-ms needs a value"},
        /* Found by fuzz/fuzz_args.c: a quoted argument broke the message's line. */
        {2, {"prog", "--\ntray"}, "unknown argument '--?tray'"},
        {4, {"prog", "--link-timeout-s", "1\n\x1b[2J", "--device"}, "'1??[2J' is not"},
    };
    gp_args args;
    char error[256];
    for (unsigned i = 0; i < sizeof rows / sizeof rows[0]; i++) {
        CHECK_INT(parse(rows[i].argc, rows[i].argv, &args, error), -1);
        CHECK_CONTAINS(error, rows[i].message);
    }
    const char *timeout[] = {"prog", "--device", "x", "--link-timeout-s", "-1"};
    CHECK_INT(parse(5, timeout, &args, error), -1);
    CHECK_CONTAINS(error, "--link-timeout-s '-1'");
    const char *retransmit[] = {"prog", "--device", "x", "--retransmit-ms", "1.5"};
    CHECK_INT(parse(5, retransmit, &args, error), -1);
    CHECK_CONTAINS(error, "--retransmit-ms '1.5'");
}
