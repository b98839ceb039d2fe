/*
 * canfdi_ctrl_mode.h — the output modes every canfdi controller accepts from
 * the application / fault-tolerance manager, one per step.
 *
 *   RUN     closed loop; the output is the control law's.
 *   FREEZE  the output is held at the last value (e.g. while the actuator
 *           manager switches H-bridges); the loops track the held output,
 *           so RUN resumes from it without a jump (bumpless).
 *   TRACK   the caller says which output the plant really receives (a
 *           substitute value, another controller's output); the loops track
 *           it as for FREEZE.
 *   OFF     the drive is off (bridge disabled, limp-home): output 0, the
 *           loops restart from the measured state, so re-enabling starts
 *           from rest without a kick.
 * Header only: constants, no code, no memory.
 */
#ifndef CANFDI_CTRL_MODE_H
#define CANFDI_CTRL_MODE_H

#define CANFDI_CTRL_RUN 0U
#define CANFDI_CTRL_FREEZE 1U
#define CANFDI_CTRL_TRACK 2U
#define CANFDI_CTRL_OFF 3U

#endif /* CANFDI_CTRL_MODE_H */
