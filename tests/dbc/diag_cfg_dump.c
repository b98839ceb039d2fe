/*
 * diag_cfg_dump.c — prints the diagnosis' default parameter thresholds as
 * JSON, from the firmware itself (canfdi_diagnosis_default_cfg), for
 * tests/dbc/test_diagnosis_rules.py: the test compares the rule table with
 * the measured symptoms at the thresholds the firmware really uses.
 */
#include <stdio.h>

#include "diag/canfdi_diagnosis.h"

static const char *const dcm_par[CANFDI_SYM_N_PAR] = {"RA", "PSI", "J", "FRICTION"};
static const char *const thr_par[CANFDI_SYM_N_PAR] = {"R", "K", "SPRING", "FRICTION"};

int main(void)
{
  canfdi_diagnosis_cfg_t c;
  unsigned i;
  canfdi_diagnosis_default_cfg(&c);
  printf("{\"jpsi\": %ld", (long)c.jpsi_q16);
  for (i = 0U; i < CANFDI_SYM_N_PAR; i++) {
    printf(", \"dcm %s pos\": %ld, \"dcm %s neg\": %ld", dcm_par[i], (long)c.dcm_par_pos_q16[i], dcm_par[i],
           (long)c.dcm_par_neg_q16[i]);
    printf(", \"thr %s pos\": %ld, \"thr %s neg\": %ld", thr_par[i], (long)c.thr_par_pos_q16[i], thr_par[i],
           (long)c.thr_par_neg_q16[i]);
  }
  printf("}\n");
  return 0;
}
