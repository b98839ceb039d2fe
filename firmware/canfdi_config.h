/*
 * canfdi_config.h — build-time configuration of the canfdi firmware.
 *
 * Every option has a default here. To override, define
 * CANFDI_CONFIG_HEADER="my_config.h" on the compiler command line; that header
 * is included first and may define any CANFDI_CFG_* macro below.
 *
 * All memory is static: options that size arrays state their RAM cost.
 */
#ifndef CANFDI_CONFIG_H
#define CANFDI_CONFIG_H

#ifdef CANFDI_CONFIG_HEADER
#include CANFDI_CONFIG_HEADER
#endif

/* Step period of the application loop. Detectors that integrate or
 * differentiate take their time base from here. Cost: none. */
#ifndef CANFDI_CFG_STEP_US
#define CANFDI_CFG_STEP_US 1000U
#endif

/* Largest number of parameters of one estimator, 1..7. RAM cost per RLS
 * instance ~ 2 n^2 + 48 n + 64 bytes (360 bytes at 6; see
 * model/canfdi_rls.h); 5 covers the throttle's mechanical equation, 6
 * leaves one spare. */
#ifndef CANFDI_CFG_RLS_MAX_PARAMS
#define CANFDI_CFG_RLS_MAX_PARAMS 6U
#endif

#endif /* CANFDI_CONFIG_H */
