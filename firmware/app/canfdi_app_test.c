/*
 * canfdi_app_test.c — enabling conditions of the intrusive test signals;
 * the manual is the header.
 */
#include "app/canfdi_app_test.h"

#include "core/canfdi_fixp.h"
#include "core/canfdi_qconst.h"

void canfdi_app_test_default_cfg(canfdi_app_test_cfg_t *cfg)
{
  if (cfg != NULL) {
    canfdi_testsched_default_cfg(&cfg->dcm);
    canfdi_testsched_default_cfg(&cfg->thr);
    cfg->dcm_w_min_rad_s_q16 = 20 * CANFDI_Q16_ONE;
    cfg->dcm_w_max_rad_s_q16 = 350 * CANFDI_Q16_ONE;
    cfg->thr_min_rad_q16 = CANFDI_Q16_DEG(10, 1);
    cfg->thr_max_rad_q16 = CANFDI_Q16_DEG(80, 1);
  }
}

int32_t canfdi_app_test_init(canfdi_app_test_t *t, const canfdi_app_test_cfg_t *cfg)
{
  int32_t rc = -CANFDI_EINVAL;
  if ((t != NULL) && (cfg != NULL) && (cfg->dcm_w_min_rad_s_q16 >= 0) &&
      (cfg->dcm_w_min_rad_s_q16 < cfg->dcm_w_max_rad_s_q16) && (cfg->thr_min_rad_q16 < cfg->thr_max_rad_q16) &&
      (canfdi_testsched_init(&t->dcm, &cfg->dcm) == CANFDI_OK) &&
      (canfdi_testsched_init(&t->thr, &cfg->thr) == CANFDI_OK)) {
    rc = CANFDI_OK;
  }
  return rc;
}

static bool within(int32_t x, int32_t lo, int32_t hi) { return (x >= lo) && (x <= hi); }

void canfdi_app_test_step(canfdi_app_test_t *t, const canfdi_app_test_cfg_t *cfg, const canfdi_app_test_in_t *dcm,
                          const canfdi_app_test_in_t *thr, bool *dcm_on, bool *thr_on)
{
  bool dcm_en;
  bool thr_en;
  CANFDI_ASSERT((t != NULL) && (cfg != NULL) && (dcm != NULL) && (thr != NULL) && (dcm_on != NULL) &&
                (thr_on != NULL));
  dcm_en = dcm->closed_loop && dcm->ref_usable &&
           within(canfdi_q31_abs(dcm->ref_q16), cfg->dcm_w_min_rad_s_q16, cfg->dcm_w_max_rad_s_q16);
  thr_en = thr->closed_loop && thr->ref_usable && within(thr->ref_q16, cfg->thr_min_rad_q16, cfg->thr_max_rad_q16);
  *dcm_on = canfdi_testsched_step(&t->dcm, dcm_en, dcm->excited, dcm->need, dcm->unlearnt);
  *thr_on = canfdi_testsched_step(&t->thr, thr_en, thr->excited, thr->need, thr->unlearnt);
}
