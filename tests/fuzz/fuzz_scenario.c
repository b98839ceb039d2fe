/*
 * fuzz_scenario.c — the SIL scenario parser (host_sim/canfdi_sim_scenario.c,
 * host_sim/SCENARIO.md) on arbitrary text, and, when it accepts the text,
 * the simulator set up from it (canfdi_sim_scn_setup).
 * Invariants: the parser returns CANFDI_OK or -CANFDI_EINVAL, and a
 * rejection carries a NUL-terminated message.
 */
#include <string.h>

#include "canfdi_sim.h"
#include "canfdi_sim_scenario.h"
#include "core/canfdi_common.h"
#include "fuzz_input.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static canfdi_sim_scn_t scn;
static canfdi_sim_t sim;

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
  canfdi_sim_scn_err_t err;
  char *text = malloc(size + 1U);
  if (text == NULL) {
    return 0;
  }
  memcpy(text, data, size);
  text[size] = '\0';
  memset(&err, 0, sizeof err);
  const int rc = canfdi_sim_scn_parse(&scn, text, "fuzz", &err);
  FZ_CHECK(rc == CANFDI_OK || rc == -CANFDI_EINVAL, "parse %d", rc);
  if (rc != CANFDI_OK) {
    FZ_CHECK(memchr(err.msg, '\0', sizeof err.msg) != NULL && err.msg[0] != '\0', "%s", "no message");
  } else {
    (void)canfdi_sim_scn_setup(&scn, &sim);
  }
  free(text);
  return 0;
}
