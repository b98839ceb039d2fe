/*
 * canfdi_ecu_cli.c — canfdi-ecu's command line; see canfdi_ecu_cli.h.
 */
#include "port/linux/canfdi_ecu_cli.h"

#include <getopt.h>
#include <stdlib.h>
#include <string.h>

void canfdi_ecu_usage(FILE *f)
{
  fprintf(f,
          "usage: " CANFDI_ECU_PROG " [-c IFACE] [--lockstep] [--nvm FILE] [--duration S]\n"
          "                  [--stats FILE.json] [-q]\n"
          "\n"
          "The canfdi supervisor (firmware/app) as a Linux process on SocketCAN.\n"
          "\n"
          "options:\n"
          "  -c, --channel IFACE  CAN interface (default: $CAN_CHANNEL, else vcan0)\n"
          "  --lockstep           step on SimStep frames (0x611) of canfdi-sim --lockstep;\n"
          "                       the ECU's frames are then bit-identical to SIL\n"
          "  --realtime           a step every 1 ms of CLOCK_MONOTONIC (the default)\n"
          "  --clock IFACE        lockstep: also take SimStep from IFACE, a clock line\n"
          "                       apart from the bus, so that the bus interface can go\n"
          "                       down (or bus-off) while the ECU keeps stepping; the\n"
          "                       bus's frames are always handled before a tick\n"
          "  --nvm FILE           keep the DTC memory in FILE (created if missing): loaded\n"
          "                       at start, stored at exit and every 10 s when changed\n"
          "  --duration S         stop after S seconds (default: run until SIGINT/SIGTERM)\n"
          "  --stats FILE.json    write run statistics at exit (steps, deadline misses,\n"
          "                       frames, step time and wake-up latency percentiles)\n"
          "  -q, --quiet          only the ready line and errors on stderr\n"
          "  -h, --help           this text\n"
          "\n"
          "Prints '" CANFDI_ECU_PROG ": ready on IFACE (lockstep|realtime)' on stderr once the\n"
          "socket is bound. SIGINT/SIGTERM: finish the step, store NVM, write stats,\n"
          "exit 0. Exit 1: runtime failure (no interface, NVM file unusable, socket\n"
          "failing for 5 s; a down interface is not a failure: the ECU keeps stepping\n"
          "and names the lost frames); 2: bad usage.\n"
          "\n"
          "examples:\n"
          "  " CANFDI_ECU_PROG " -c vcan0                       realtime, until Ctrl-C\n"
          "  " CANFDI_ECU_PROG " --lockstep & canfdi-sim --can vcan0 --lockstep -s SCN\n"
          "  " CANFDI_ECU_PROG " --nvm /tmp/ecu.nvm --duration 60 --stats /tmp/ecu.json\n"
          "  tools/vcan-run " CANFDI_ECU_PROG " --duration 2 -q     where the kernel lacks vcan\n"
          "  chrt -f 80 build/bin/canfdi-ecu-rel --stats rt.json   timing figures\n");
}

/* Seconds, decimal without exponent (e.g. 2, 0.5, 60; at most 9 fraction
 * digits), parsed in integers. Returns false when not a number in
 * (0, 10^7]. */
static bool parse_seconds(const char *s, int64_t *ns)
{
  int64_t whole = 0;
  int64_t frac = 0;
  int64_t scale = 100000000;
  const char *p = s;
  bool digits = false;
  while ((*p >= '0') && (*p <= '9')) {
    whole = (whole * 10) + (int64_t)(*p - '0');
    digits = true;
    if (whole > 10000000) {
      return false;
    }
    p++;
  }
  if (*p == '.') {
    p++;
    while ((*p >= '0') && (*p <= '9')) {
      if (scale == 0) {
        return false;
      }
      frac += (int64_t)(*p - '0') * scale;
      scale /= 10;
      digits = true;
      p++;
    }
  }
  *ns = (whole * 1000000000) + frac;
  return digits && (*p == '\0') && (*ns > 0) && (*ns <= (int64_t)10000000 * 1000000000);
}

int canfdi_ecu_parse_args(int argc, char **argv, canfdi_ecu_opts_t *o)
{
  enum { OPT_LOCKSTEP = 256, OPT_REALTIME, OPT_NVM, OPT_DURATION, OPT_STATS, OPT_CLOCK };
  static const struct option opts[] = {
      {"channel", required_argument, NULL, 'c'},
      {"lockstep", no_argument, NULL, OPT_LOCKSTEP},
      {"realtime", no_argument, NULL, OPT_REALTIME},
      {"nvm", required_argument, NULL, OPT_NVM},
      {"duration", required_argument, NULL, OPT_DURATION},
      {"stats", required_argument, NULL, OPT_STATS},
      {"clock", required_argument, NULL, OPT_CLOCK},
      {"quiet", no_argument, NULL, 'q'},
      {"help", no_argument, NULL, 'h'},
      {NULL, 0, NULL, 0},
  };
  const char *env = getenv("CAN_CHANNEL");
  int opt;
  memset(o, 0, sizeof *o);
  o->iface = ((env != NULL) && (env[0] != '\0')) ? env : "vcan0";
  while ((opt = getopt_long(argc, argv, "c:qh", opts, NULL)) != -1) {
    switch (opt) {
    case 'c':
      o->iface = optarg;
      break;
    case OPT_LOCKSTEP:
      o->lockstep = true;
      break;
    case OPT_REALTIME:
      o->lockstep = false;
      break;
    case OPT_NVM:
      o->nvm_path = optarg;
      break;
    case OPT_DURATION:
      if (!parse_seconds(optarg, &o->duration_ns)) {
        fprintf(stderr, CANFDI_ECU_PROG ": --duration wants seconds > 0, got '%s'\n", optarg);
        return CANFDI_ECU_ARGS_USAGE;
      }
      break;
    case OPT_STATS:
      o->stats_path = optarg;
      break;
    case OPT_CLOCK:
      o->clock_iface = optarg;
      break;
    case 'q':
      o->quiet = true;
      break;
    case 'h':
      canfdi_ecu_usage(stdout);
      return CANFDI_ECU_ARGS_HELP;
    default:
      fprintf(stderr, CANFDI_ECU_PROG ": bad usage (see " CANFDI_ECU_PROG " --help)\n");
      return CANFDI_ECU_ARGS_USAGE;
    }
  }
  if (optind < argc) {
    fprintf(stderr, CANFDI_ECU_PROG ": unexpected argument '%s' (see " CANFDI_ECU_PROG " --help)\n",
            argv[optind]);
    return CANFDI_ECU_ARGS_USAGE;
  }
  if ((o->iface[0] == '\0') || (strlen(o->iface) >= 16U)) {
    fprintf(stderr, CANFDI_ECU_PROG ": bad interface name '%s'\n", o->iface);
    return CANFDI_ECU_ARGS_USAGE;
  }
  if ((o->clock_iface != NULL) &&
      (!o->lockstep || (o->clock_iface[0] == '\0') || (strlen(o->clock_iface) >= 16U))) {
    fprintf(stderr, CANFDI_ECU_PROG ": --clock wants --lockstep and an interface name, got '%s'\n",
            o->clock_iface);
    return CANFDI_ECU_ARGS_USAGE;
  }
  return CANFDI_ECU_ARGS_RUN;
}
