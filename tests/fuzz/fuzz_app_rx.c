/*
 * fuzz_app_rx.c — frame reception through the whole application: received
 * frames (sensor and setpoint frames, E2E-protected or not, any length, any
 * identifier) into canfdi_app_rx_frame (input supervision, E2E check,
 * plausibility), interleaved with 1 ms canfdi_app_step calls at a jittered
 * time base (the model, diagnosis, DTC memory and transmit scheduler run on
 * what was accepted). The UDS identifiers are fuzz_uds's.
 *
 * The input is a sequence of operations (tests/fuzz/README.md):
 *   0-2  a protected frame: identifier of a sensor/setpoint frame, 7
 *        payload bytes, counter step (mostly +1), CRC made right (or, for
 *        one in 16, one bit wrong) — gets past E2E into the supervision;
 *   3    a raw frame: any 11-bit identifier, DLC 0..8, any bytes;
 *   4-7  steps: 1..16 ms, each at 1000 us +- a jitter byte.
 *
 * Invariants after every step: the step succeeds with 2..CANFDI_APP_MAX_TX
 * frames, the actuator frames first; every frame is 8 bytes of an
 * identifier the ECU sends; the E2E CRC of every protected frame (the
 * actuators, EcuStatus, EcuDiagnosis, EcuDtc) is right; every
 * signal of every frame sent decodes within its DBC range
 * (fuzz_ranges.c, generated from the DBC); the DTC memory's invariants hold.
 * The step's cost on hostile input is checked outside libFuzzer: `make
 * pil-cost` writes these inputs out as logs (FUZZ_EXPORT_LOG,
 * fuzz_export.h) and counts each step's instructions on the Cortex-M cores.
 */
#include <string.h>

#include "app/canfdi_app.h"
#include "comm/canfdi_e2e.h"
#include "comm/gen/canfdi_msg.h"
#include "fuzz_input.h"
#include "fuzz_ranges.h"
#ifdef FUZZ_EXPORT_LOG
#include "fuzz_export.h" /* the inputs as logs for the step-cost check */
#endif

#define MAX_OPS 256U
#define MAX_STEPS 600U

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static canfdi_app_t app;
static canfdi_app_t pristine;
static canfdi_app_cal_t cal;

static const uint32_t rx_ids[] = {CANFDI_MSG_DCM_SENSOR_FRAME_ID, CANFDI_MSG_THR_SENSOR_FRAME_ID,
                                  CANFDI_MSG_SETPOINT_DCM_FRAME_ID, CANFDI_MSG_SETPOINT_THR_FRAME_ID};
#define N_RX (sizeof rx_ids / sizeof rx_ids[0])

static struct {
  uint32_t now_us;
  uint32_t steps;
  uint8_t counter[N_RX];
} t;

static bool ecu_sends(uint32_t id)
{
  switch (id) {
  case CANFDI_MSG_DCM_ACTUATOR_FRAME_ID:
  case CANFDI_MSG_THR_ACTUATOR_FRAME_ID:
  case CANFDI_MSG_ECU_RESIDUAL_DCM_FRAME_ID:
  case CANFDI_MSG_ECU_RESIDUAL_THR_FRAME_ID:
  case CANFDI_MSG_ECU_STATUS_FRAME_ID:
  case CANFDI_MSG_ECU_DIAGNOSIS_FRAME_ID:
  case CANFDI_MSG_ECU_SELF_DIAG_FRAME_ID:
  case CANFDI_MSG_ECU_DTC_FRAME_ID:
  case CANFDI_MSG_ECU_PARAM_DCM_FRAME_ID:
  case CANFDI_MSG_ECU_PARAM_THR_FRAME_ID:
  case CANFDI_MSG_UDS_PHYS_RESP_FRAME_ID: return true;
  default: return false;
  }
}

static void check_dtc(void)
{
  const canfdi_dtc_t *m = &app.dtc;
  FZ_CHECK(canfdi_dtc_invariants_hold(m), "%s", "DTC memory invariants");
  for (uint8_t i = 0U; i < (uint8_t)CANFDI_DTC_COUNT; i++) {
    const int32_t s = canfdi_dtc_status(m, i);
    if ((s & 0x0C) != 0) {
      FZ_CHECK((s & 0x20) != 0, "DTC %u: status %02X confirmed/pending without TFSLC", i, (unsigned)s);
    }
  }
}

static void step(int32_t jitter_us)
{
  canfdi_tx_frame_t out[CANFDI_APP_MAX_TX];
  t.now_us += (uint32_t)(1000 + jitter_us);
  t.steps++;
  const int32_t n = canfdi_app_step(&app, t.now_us, out);
  FZ_CHECK(n >= 2 && n <= (int32_t)CANFDI_APP_MAX_TX, "step returned %d", (int)n);
  FZ_CHECK(out[0].id == CANFDI_MSG_DCM_ACTUATOR_FRAME_ID && out[1].id == CANFDI_MSG_THR_ACTUATOR_FRAME_ID,
           "first frames %03X %03X", (unsigned)out[0].id, (unsigned)out[1].id);
  for (int32_t i = 0; i < n; i++) {
    const char *bad = NULL;
    FZ_CHECK(ecu_sends(out[i].id) && out[i].dlc == 8U, "frame %03X dlc %u", (unsigned)out[i].id, out[i].dlc);
    if ((i < 2) || (out[i].id == CANFDI_MSG_ECU_STATUS_FRAME_ID) ||
        (out[i].id == CANFDI_MSG_ECU_DIAGNOSIS_FRAME_ID) || (out[i].id == CANFDI_MSG_ECU_DTC_FRAME_ID)) {
      FZ_CHECK(out[i].data[0] == canfdi_e2e_frame_crc((uint16_t)out[i].id, out[i].data, 8U),
               "E2E CRC of %03X", (unsigned)out[i].id);
    }
    FZ_CHECK(fuzz_frame_in_range(out[i].id, out[i].data, out[i].dlc, &bad), "frame %03X: %s out of its DBC range",
             (unsigned)out[i].id, bad != NULL ? bad : "?");
  }
  check_dtc();
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
  static bool ready = false;
  fz_in_t in = {data, size, 0U};
  if (!ready) {
    canfdi_app_default_cal(&cal);
    if (canfdi_app_init(&app, &cal, 0U) != CANFDI_OK) {
      abort();
    }
    memcpy(&pristine, &app, sizeof app);
    ready = true;
  }
  memcpy(&app, &pristine, sizeof app);
  memset(&t, 0, sizeof t);
  for (uint32_t op = 0U; fz_left(&in) && (op < MAX_OPS) && (t.steps < MAX_STEPS); op++) {
    const uint8_t o = fz_u8(&in);
    switch (o % 8U) {
    case 0U:
    case 1U:
    case 2U: {
      uint8_t f[8];
      const uint8_t b = fz_u8(&in);
      const uint32_t k = b % N_RX;
      for (uint32_t j = 1U; j < 8U; j++) {
        f[j] = fz_u8(&in);
      }
      /* the counter: +1 mostly, else the step the input says */
      t.counter[k] = (uint8_t)((t.counter[k] + (((b >> 2) < 48U) ? 1U : ((b >> 2) & 15U))) & 15U);
      f[1] = (uint8_t)((f[1] & 0xF0U) | t.counter[k]);
      f[0] = canfdi_e2e_frame_crc((uint16_t)rx_ids[k], f, 8U);
      if ((b & 0xF0U) == 0xF0U) {
        f[0] ^= (uint8_t)(1U << (b & 7U));
      }
      (void)canfdi_app_rx_frame(&app, rx_ids[k], f, 8U, t.now_us);
      break;
    }
    case 3U: {
      uint8_t f[8];
      uint32_t id = fz_u16(&in) & 0x7FFU;
      const uint8_t dlc = (uint8_t)(fz_u8(&in) % 9U);
      if ((id == CANFDI_MSG_UDS_PHYS_REQ_FRAME_ID) || (id == CANFDI_MSG_UDS_FUNC_REQ_FRAME_ID)) {
        id = rx_ids[id % N_RX];
      }
      for (uint32_t j = 0U; j < 8U; j++) {
        f[j] = (j < dlc) ? fz_u8(&in) : 0U;
      }
      (void)canfdi_app_rx_frame(&app, id, f, dlc, t.now_us);
      break;
    }
    default: {
      const uint8_t b = fz_u8(&in);
      const uint32_t n = 1U + (b & 15U);
      const int32_t jitter = ((int32_t)(b >> 4) - 8) * 25; /* -200..+175 us */
      for (uint32_t j = 0U; (j < n) && (t.steps < MAX_STEPS); j++) {
        step(jitter);
      }
      break;
    }
    }
  }
  return 0;
}
