/*
 * canfdi_ecu_cli.h — canfdi-ecu's command line: options, usage text and
 * their parsing (integer arithmetic only: firmware/ holds no floating
 * point, not even in a port).
 */
#ifndef CANFDI_ECU_CLI_H
#define CANFDI_ECU_CLI_H

#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

#define CANFDI_ECU_PROG "canfdi-ecu"

typedef struct {
  const char *iface;      /* CAN interface (default $CAN_CHANNEL, else vcan0) */
  const char *nvm_path;   /* --nvm FILE or NULL */
  const char *stats_path; /* --stats FILE.json or NULL */
  const char *clock_iface; /* --clock IFACE (lockstep: SimStep also from IFACE) or NULL */
  int64_t duration_ns;    /* --duration; 0: until signalled */
  bool lockstep;          /* --lockstep (default realtime) */
  bool quiet;             /* -q */
} canfdi_ecu_opts_t;

/* Result of canfdi_ecu_parse_args. */
#define CANFDI_ECU_ARGS_RUN 0   /* options in *o: run */
#define CANFDI_ECU_ARGS_HELP 1  /* --help printed on stdout: exit 0 */
#define CANFDI_ECU_ARGS_USAGE 2 /* bad usage, message on stderr: exit 2 */

/* Parses argv into *o (defaults first). Returns CANFDI_ECU_ARGS_*. */
int canfdi_ecu_parse_args(int argc, char **argv, canfdi_ecu_opts_t *o);

/* The usage text with examples. */
void canfdi_ecu_usage(FILE *f);

#endif /* CANFDI_ECU_CLI_H */
