/*
 * canfdi_app_uds.h — the application's side of the diagnostic server
 * (uds/canfdi_uds.h): the stage that steps the server with a view of this
 * step's values, and what the server's decisions do to the next step.
 *
 *   canfdi_app_uds_stage   after the outputs: the server's step (timers, at
 *                          most one request answered, at most one ISO-TP
 *                          frame, encoded as UdsPhysResp and appended to the
 *                          step's frames); while CommunicationControl has
 *                          the monitoring frames off, only the actuator
 *                          frames and the server's frame stay in the step
 *   canfdi_app_uds_apply   at the start of the next step: the estimator
 *                          resets the server asked for
 * The actuator test's references and the spring check's release are read
 * by the control and manager stages from app->uds_act (the feedback of
 * the last step, like canfdi_app_fb_t). An answered ECUReset sets
 * app->reset_requested (canfdi_app_reset_requested) for the port.
 * Cost: the server's step (uds/canfdi_uds.h) plus filling its view (a
 * dozen pointer and counter copies). No state of its own.
 */
#ifndef CANFDI_APP_UDS_H
#define CANFDI_APP_UDS_H

#include "app/canfdi_app.h"

/* The stage: appends at most one frame to out[0..n); returns the new n. */
int32_t canfdi_app_uds_stage(canfdi_app_t *app, canfdi_tx_frame_t *out, int32_t n);

/* The estimator resets of the last step's decisions. */
void canfdi_app_uds_apply(canfdi_app_t *app);

#endif /* CANFDI_APP_UDS_H */
