/*
 * harness.c — a line-oriented driver that lets tests/dbc compare the C E2E
 * module and the generated C codecs with their Python counterparts
 * (crccheck, tools/canfdi/e2e.py, cantools). Built by test_crosscheck.py
 * with the project's warning flags and sanitizers.
 *
 * Commands on stdin, one per line, answers on stdout:
 *   crc ID HEX                -> CRC of the frame (canfdi_e2e_frame_crc)
 *   init ID MAXDELTA          -> "ok"
 *   chk HEX|-                 -> "STATUS LOST" (canfdi_e2e_check; - = no frame)
 *   tx MSG COUNTER R1 R2 ...  -> HEX: sender packs raw values, then protects
 *   rx MSG HEX                -> "R1 R2 ...": receiver unpacks raw values;
 *                                for sensor frames a last field says whether
 *                                every signal lies in its canfdi_raw_limits.h range
 * MSG is dcm_sensor | thr_sensor (PLANT packs, ECU unpacks) or
 * dcm_actuator | thr_actuator (ECU packs, PLANT unpacks).
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "canfdi_sim_msg.h"
#include "comm/canfdi_e2e.h"
#include "comm/gen/canfdi_msg.h"
#include "comm/gen/canfdi_raw_limits.h"

#define IN_RANGE(v, base) (((v) >= base##_MIN) && ((v) <= base##_MAX))

static size_t parse_hex(const char *s, uint8_t *out, size_t cap)
{
  size_t n = 0U;
  while ((s[0] != '\0') && (s[1] != '\0') && (n < cap)) {
    char pair[3] = {s[0], s[1], '\0'};
    out[n++] = (uint8_t)strtoul(pair, NULL, 16);
    s += 2;
  }
  return n;
}

static void print_hex(const uint8_t *d, size_t n)
{
  for (size_t i = 0U; i < n; i++) {
    printf("%02x", d[i]);
  }
  printf("\n");
}

static unsigned long field(const char *tok)
{
  return (tok != NULL) ? strtoul(tok, NULL, 0) : 0UL;
}

static int do_tx(const char *msg, unsigned long counter)
{
  uint8_t f[8] = {0};
  uint16_t id = 0U;
  int n = -1;
  if (strcmp(msg, "dcm_sensor") == 0) {
    struct canfdi_sim_msg_dcm_sensor_t m = {0};
    m.dcm_ua = (uint16_t)field(strtok(NULL, " \n"));
    m.dcm_ia = (uint16_t)field(strtok(NULL, " \n"));
    m.dcm_omega = (uint16_t)field(strtok(NULL, " \n"));
    m.dcm_usupply = (uint16_t)field(strtok(NULL, " \n"));
    n = canfdi_sim_msg_dcm_sensor_pack(f, &m, sizeof f);
    id = CANFDI_SIM_MSG_DCM_SENSOR_FRAME_ID;
  } else if (strcmp(msg, "thr_sensor") == 0) {
    struct canfdi_sim_msg_thr_sensor_t m = {0};
    m.thr_tps1 = (uint16_t)field(strtok(NULL, " \n"));
    m.thr_tps2 = (uint16_t)field(strtok(NULL, " \n"));
    m.thr_imot = (uint16_t)field(strtok(NULL, " \n"));
    m.thr_usupply = (uint16_t)field(strtok(NULL, " \n"));
    n = canfdi_sim_msg_thr_sensor_pack(f, &m, sizeof f);
    id = CANFDI_SIM_MSG_THR_SENSOR_FRAME_ID;
  } else if (strcmp(msg, "dcm_actuator") == 0) {
    struct canfdi_msg_dcm_actuator_t m = {0};
    m.dcm_bridge_sel = (uint8_t)field(strtok(NULL, " \n"));
    m.dcm_enable = (uint8_t)field(strtok(NULL, " \n"));
    m.dcm_ua_cmd = (uint16_t)field(strtok(NULL, " \n"));
    n = canfdi_msg_dcm_actuator_pack(f, &m, sizeof f);
    id = CANFDI_MSG_DCM_ACTUATOR_FRAME_ID;
  } else if (strcmp(msg, "thr_actuator") == 0) {
    struct canfdi_msg_thr_actuator_t m = {0};
    m.thr_enable = (uint8_t)field(strtok(NULL, " \n"));
    m.thr_u_cmd = (uint16_t)field(strtok(NULL, " \n"));
    n = canfdi_msg_thr_actuator_pack(f, &m, sizeof f);
    id = CANFDI_MSG_THR_ACTUATOR_FRAME_ID;
  }
  if (n != 8) {
    return 1;
  }
  canfdi_e2e_tx_t tx;
  canfdi_e2e_tx_init(&tx, id);
  tx.counter = (uint8_t)(counter & 15U);
  if (canfdi_e2e_protect(&tx, f, sizeof f) != CANFDI_OK) {
    return 1;
  }
  print_hex(f, sizeof f);
  return 0;
}

static int do_rx(const char *msg, const uint8_t *f, size_t n)
{
  int rc = -1;
  if (strcmp(msg, "dcm_sensor") == 0) {
    struct canfdi_msg_dcm_sensor_t m;
    rc = canfdi_msg_dcm_sensor_unpack(&m, f, n);
    /* The CRC and counter limits are the full type range; comparing an
     * unsigned value with >= 0U would warn, so only the payload is checked. */
    const int ok = IN_RANGE(m.dcm_ua, CANFDI_RAW_DCM_SENSOR_DCM_UA) &&
                   IN_RANGE(m.dcm_ia, CANFDI_RAW_DCM_SENSOR_DCM_IA) &&
                   IN_RANGE(m.dcm_omega, CANFDI_RAW_DCM_SENSOR_DCM_OMEGA) &&
                   (m.dcm_usupply <= CANFDI_RAW_DCM_SENSOR_DCM_USUPPLY_MAX);
    printf("%u %u %u %u %u %u %d\n", m.dcm_sensor_crc, m.dcm_sensor_counter, m.dcm_ua, m.dcm_ia,
           m.dcm_omega, m.dcm_usupply, ok);
  } else if (strcmp(msg, "thr_sensor") == 0) {
    struct canfdi_msg_thr_sensor_t m;
    rc = canfdi_msg_thr_sensor_unpack(&m, f, n);
    const int ok = (m.thr_tps1 <= CANFDI_RAW_THR_SENSOR_THR_TPS1_MAX) &&
                   (m.thr_tps2 <= CANFDI_RAW_THR_SENSOR_THR_TPS2_MAX) &&
                   IN_RANGE(m.thr_imot, CANFDI_RAW_THR_SENSOR_THR_IMOT) &&
                   (m.thr_usupply <= CANFDI_RAW_THR_SENSOR_THR_USUPPLY_MAX);
    printf("%u %u %u %u %u %u %d\n", m.thr_sensor_crc, m.thr_sensor_counter, m.thr_tps1, m.thr_tps2,
           m.thr_imot, m.thr_usupply, ok);
  } else if (strcmp(msg, "dcm_actuator") == 0) {
    struct canfdi_sim_msg_dcm_actuator_t m;
    rc = canfdi_sim_msg_dcm_actuator_unpack(&m, f, n);
    printf("%u %u %u %u %u\n", m.dcm_actuator_crc, m.dcm_actuator_counter, m.dcm_bridge_sel,
           m.dcm_enable, m.dcm_ua_cmd);
  } else if (strcmp(msg, "thr_actuator") == 0) {
    struct canfdi_sim_msg_thr_actuator_t m;
    rc = canfdi_sim_msg_thr_actuator_unpack(&m, f, n);
    printf("%u %u %u %u\n", m.thr_actuator_crc, m.thr_actuator_counter, m.thr_enable, m.thr_u_cmd);
  }
  return (rc == 0) ? 0 : 1;
}

int main(void)
{
  char line[512];
  canfdi_e2e_rx_t rx;
  (void)canfdi_e2e_rx_init(&rx, 0U, 1U);
  while (fgets(line, (int)sizeof line, stdin) != NULL) {
    const char *cmd = strtok(line, " \n");
    uint8_t f[64];
    int bad = 0;
    if (cmd == NULL) {
      continue;
    }
    if (strcmp(cmd, "crc") == 0) {
      const uint16_t id = (uint16_t)field(strtok(NULL, " \n"));
      const size_t n = parse_hex(strtok(NULL, " \n"), f, sizeof f);
      printf("%u\n", canfdi_e2e_frame_crc(id, f, n));
    } else if (strcmp(cmd, "init") == 0) {
      const uint16_t id = (uint16_t)field(strtok(NULL, " \n"));
      bad = canfdi_e2e_rx_init(&rx, id, (uint8_t)field(strtok(NULL, " \n"))) != CANFDI_OK;
      printf("ok\n");
    } else if (strcmp(cmd, "chk") == 0) {
      const char *h = strtok(NULL, " \n");
      int st;
      if (strcmp(h, "-") == 0) {
        st = canfdi_e2e_check(&rx, NULL, 0U);
      } else {
        st = canfdi_e2e_check(&rx, f, parse_hex(h, f, sizeof f));
      }
      printf("%d %u\n", st, rx.lost);
    } else if (strcmp(cmd, "tx") == 0) {
      const char *msg = strtok(NULL, " \n");
      bad = do_tx(msg, field(strtok(NULL, " \n")));
    } else if (strcmp(cmd, "rx") == 0) {
      const char *msg = strtok(NULL, " \n");
      const size_t n = parse_hex(strtok(NULL, " \n"), f, sizeof f);
      bad = do_rx(msg, f, n);
    } else {
      bad = 1;
    }
    if (bad) {
      fprintf(stderr, "harness: bad command\n");
      return 2;
    }
    fflush(stdout);
  }
  return 0;
}
