/*
 * canfdi_isotp.h — ISO 15765-2 (ISO-TP) transport of the ECU's diagnostic
 * server: one physical connection (requests on UdsPhysReq 0x7E0, responses
 * on UdsPhysResp 0x7E8) and functional reception (UdsFuncReq 0x7DF, single
 * frames only), over static buffers sized by configuration. No heap.
 *
 * Frames. Every frame carries CANFDI_CFG_ISOTP_FRAME_BYTES (CAN_DL) bytes;
 * received frames are unpacked and sent frames packed by the codec generated
 * from dbc/canfdi.dbc (the ISO-TP bytes are the content of the frame's one
 * 64-bit signal, byte 0 first). Sent frames are padded to CAN_DL with
 * CANFDI_CFG_ISOTP_PAD_BYTE (ISO 15765-2 mandatory padding); a received
 * frame shorter than CAN_DL is not a frame of this connection: ignored and
 * counted (diag.short_frames). Protocol control information (PCI):
 *   single frame (SF)       0x0L + L data bytes, L = 1..CAN_DL-1 (CAN_DL
 *                           8); with CAN_DL > 8 also the escape 0x00 LL
 *   first frame (FF)        0x1H LL (12-bit length >= CAN_DL) or the escape
 *                           0x10 0x00 + 32-bit length, then data
 *   consecutive frame (CF)  0x2N, N the sequence number 1, 2, .. 15, 0, ..
 *   flow control (FC)       0x3S BS STmin, S = 0 continue to send, 1 wait,
 *                           2 overflow
 * The frame length is a configuration (8 today, the DBC's DLC): the same
 * code parses and builds CAN FD's escape forms when CAN_DL is above 8
 * (the DBC's UDS frames would then grow to that length).
 *
 * Reception (physical). SF: the message is complete. FF: a length above
 * CANFDI_CFG_ISOTP_RX_BYTES is answered with FC overflow and dropped
 * (diag.rx_overflow); else FC continue-to-send with cfg.bs and cfg.stmin,
 * then CFs; after every cfg.bs CFs (0: none) another FC. Errors, each
 * counted, all ending the reception without a response (ISO 15765-2
 * N_UNEXP_PDU, N_WRONG_SN, N_TIMEOUT_Cr): an SF/FF length outside its
 * range or beyond the frame (diag.bad_length), a CF with the wrong
 * sequence number (diag.wrong_sn), no CF within cfg.n_cr_ms (diag.timeout_cr),
 * a CF while no reception runs (diag.unexpected, ignored), a new SF/FF
 * during a reception (diag.rx_restarted: the new one starts), an unknown
 * PCI type (diag.unexpected).
 * Complete single-frame requests (physical or functional) wait in a queue
 * of CANFDI_CFG_ISOTP_SF_QUEUE entries, in arrival order, so that requests
 * sent back to back (a TesterPresent with suppressed response, then the
 * next request, within one step), or while a response is being sent, are
 * all answered, one per step; a full queue drops the new one
 * (diag.busy_dropped). A first frame while a segmented request waits for
 * the server or a response is being sent is dropped the same way (the
 * tester's N_Bs expires): the server answers one request at a time.
 * Reception (functional): single frames only; FF, CF and FC on 0x7DF are
 * ignored and counted (diag.func_ignored).
 *
 * Transmission. canfdi_isotp_send() after writing the response into
 * canfdi_isotp_tx_buf(): up to CAN_DL - 1 bytes as an SF, else an FF, then
 * CFs as the tester's FC allows: its block size, its STmin (0x00..0x7F ms;
 * 0xF1..0xF9 (100..900 us) and 0: the next step; a reserved value counts as
 * 0x7F, as ISO 15765-2 prescribes). At most one frame leaves per 1 ms step, so
 * the spacing is max(1 ms, STmin). FC wait frames are accepted up to
 * cfg.wft_max in a row (one more ends the transfer, diag.wft_exceeded);
 * no FC within cfg.n_bs_ms ends it (diag.timeout_bs); FC overflow or an
 * invalid flow status ends it (diag.tx_aborted). An FC while no transfer
 * waits for one is ignored (diag.unexpected).
 *
 * One step (canfdi_isotp_step, every 1 ms): the timers, then at most one
 * frame to send: a pending FC of the reception first, else the next frame
 * of the transmission.
 *
 * Cost (O(1) per call, no loop longer than CAN_DL bytes): rx_frame = one
 * codec unpack + a copy of at most CAN_DL - 1 bytes; step = the timers + at
 * most one frame build (CAN_DL bytes). Measured with the application (see
 * app/canfdi_app.h for the step with a request in flight).
 * Memory: sizeof(canfdi_isotp_t) = CANFDI_CFG_ISOTP_RX_BYTES +
 * CANFDI_CFG_ISOTP_TX_BYTES + 9 x CANFDI_CFG_ISOTP_SF_QUEUE + about 112
 * bytes: 532 on Cortex-M with the defaults (128 + 256 + 36 + 112), of
 * which the counters are 64; `canfdi-sil --sizes` prints the host's.
 */
#ifndef CANFDI_ISOTP_H
#define CANFDI_ISOTP_H

#include "core/canfdi_common.h"

/* CAN_DL of every frame of the connection: 8 (classic CAN, the DBC's DLC)
 * or a CAN FD length 12..64. */
#ifndef CANFDI_CFG_ISOTP_FRAME_BYTES
#define CANFDI_CFG_ISOTP_FRAME_BYTES 8U
#endif
/* Largest request, bytes (RAM 1 byte each). A 0x22 request with 63 data
 * identifiers is 127 bytes. */
#ifndef CANFDI_CFG_ISOTP_RX_BYTES
#define CANFDI_CFG_ISOTP_RX_BYTES 128U
#endif
/* Largest response, bytes (RAM 1 byte each): 0x19 0x0A over 32 DTCs is 131. */
#ifndef CANFDI_CFG_ISOTP_TX_BYTES
#define CANFDI_CFG_ISOTP_TX_BYTES 256U
#endif
/* Single-frame requests waiting for the server (RAM 9 bytes each). */
#ifndef CANFDI_CFG_ISOTP_SF_QUEUE
#define CANFDI_CFG_ISOTP_SF_QUEUE 4U
#endif
/* Padding byte of sent frames. */
#ifndef CANFDI_CFG_ISOTP_PAD_BYTE
#define CANFDI_CFG_ISOTP_PAD_BYTE 0xCCU
#endif

#define CANFDI_ISOTP_SF_MAX (CANFDI_CFG_ISOTP_FRAME_BYTES - 1U)

/* Timing and flow control (the ISO 15765-2 defaults: N_Bs = N_Cr = 1000 ms). */
typedef struct {
  uint16_t n_bs_ms;  /* wait for the tester's FC after an FF or a block, 1..60000 */
  uint16_t n_cr_ms;  /* wait for the tester's next CF, 1..60000 */
  uint8_t bs;        /* block size announced in our FC (0: no further FC) */
  uint8_t stmin;     /* STmin announced in our FC (raw, 0x00..0x7F, 0xF1..0xF9) */
  uint8_t wft_max;   /* FC wait frames accepted in a row */
} canfdi_isotp_cfg_t;

/* Monotone counters, saturating at UINT32_MAX. */
typedef struct {
  uint32_t rx_frames;     /* frames of this connection received */
  uint32_t rx_messages;   /* complete requests (physical + functional) */
  uint32_t tx_frames;     /* frames built for sending */
  uint32_t tx_messages;   /* responses completely sent */
  uint32_t short_frames;  /* CAN_DL below the configured one */
  uint32_t bad_length;    /* SF/FF length out of range */
  uint32_t wrong_sn;      /* CF sequence error: reception ended */
  uint32_t timeout_cr;    /* no CF in time: reception ended */
  uint32_t timeout_bs;    /* no FC in time: transmission ended */
  uint32_t wft_exceeded;  /* too many FC wait frames: transmission ended */
  uint32_t tx_aborted;    /* FC overflow or invalid flow status */
  uint32_t rx_overflow;   /* FF longer than the receive buffer */
  uint32_t rx_restarted;  /* SF/FF during a reception */
  uint32_t unexpected;    /* CF/FC out of place, unknown PCI */
  uint32_t func_ignored;  /* functional FF/CF/FC */
  uint32_t busy_dropped;  /* request dropped: queue full, or a FF while busy */
} canfdi_isotp_diag_t;

typedef enum {
  CANFDI_ISOTP_RX_IDLE = 0,
  CANFDI_ISOTP_RX_RECEIVING = 1,
  CANFDI_ISOTP_RX_DONE = 2 /* a complete request waits for the server */
} canfdi_isotp_rx_state_t;

typedef enum {
  CANFDI_ISOTP_TX_IDLE = 0,
  CANFDI_ISOTP_TX_SF = 1,      /* an SF to send in the next step */
  CANFDI_ISOTP_TX_FF = 2,      /* an FF to send in the next step */
  CANFDI_ISOTP_TX_WAIT_FC = 3, /* waiting for the tester's FC */
  CANFDI_ISOTP_TX_CF = 4       /* sending CFs */
} canfdi_isotp_tx_state_t;

typedef struct {
  canfdi_isotp_cfg_t cfg;
  /* reception (physical) */
  uint8_t rx_buf[CANFDI_CFG_ISOTP_RX_BYTES];
  uint32_t rx_len;       /* announced length */
  uint32_t rx_got;       /* bytes received */
  uint16_t rx_timer_ms;  /* since the last FC sent / CF received */
  uint8_t rx_state;      /* canfdi_isotp_rx_state_t */
  uint8_t rx_sn;         /* next expected sequence number */
  uint8_t rx_block;      /* CFs left in this block (cfg.bs != 0) */
  uint8_t fc_pending;    /* 0 none, else the FC's first byte (0x30 or 0x32) */
  /* single-frame requests waiting, in arrival order */
  struct {
    uint8_t len;
    bool functional;
    uint8_t data[CANFDI_ISOTP_SF_MAX];
  } sfq[CANFDI_CFG_ISOTP_SF_QUEUE];
  uint8_t sfq_head;
  uint8_t sfq_len;
  uint8_t peeked;        /* 1: the segmented request, 2: the queue's head */
  /* transmission */
  uint8_t tx_buf[CANFDI_CFG_ISOTP_TX_BYTES];
  uint32_t tx_len;
  uint32_t tx_pos;       /* bytes sent */
  uint16_t tx_timer_ms;  /* N_Bs */
  uint8_t tx_state;      /* canfdi_isotp_tx_state_t */
  uint8_t tx_sn;
  uint8_t tx_block;      /* CFs left before the next FC (0: unlimited) */
  uint8_t tx_gap;        /* steps until the next CF may leave */
  uint8_t tx_stmin_ms;   /* the tester's STmin, whole steps */
  uint8_t tx_wft;        /* FC wait frames in a row */
  canfdi_isotp_diag_t diag;
  bool initialised;
} canfdi_isotp_t;

/* The defaults: N_Bs = N_Cr = 1000 ms, BS 0, STmin 0, 10 wait frames. */
void canfdi_isotp_default_cfg(canfdi_isotp_cfg_t *cfg);

/* Idle connection with cfg (copied). Returns CANFDI_OK or -CANFDI_EINVAL
 * (NULL, a timer of 0 or an STmin outside the ISO ranges). O(1). */
int32_t canfdi_isotp_init(canfdi_isotp_t *t, const canfdi_isotp_cfg_t *cfg);

/* Ends any reception and transmission (counters kept). O(1). */
void canfdi_isotp_reset(canfdi_isotp_t *t);

/*
 * One received CAN frame of the connection: functional (0x7DF) or physical
 * (0x7E0), data[0..dlc). Returns CANFDI_OK when the frame was taken (also
 * when the protocol ignored it: see the counters), -CANFDI_EINVAL for NULL
 * or an uninitialised t. Cost O(CAN_DL).
 */
int32_t canfdi_isotp_rx_can(canfdi_isotp_t *t, bool functional, const uint8_t *data, uint8_t dlc);

/*
 * A complete request, if one waits: sets *functional, returns its length
 * (> 0) and points *msg at it (valid until canfdi_isotp_rx_release); 0 if
 * none. A segmented request comes before the queued single frames. O(1).
 */
uint32_t canfdi_isotp_rx_peek(canfdi_isotp_t *t, const uint8_t **msg, bool *functional);

/* The server is done with the request canfdi_isotp_rx_peek returned. O(1). */
void canfdi_isotp_rx_release(canfdi_isotp_t *t);

/* True while a response is being sent (a new one must wait). */
bool canfdi_isotp_tx_busy(const canfdi_isotp_t *t);

/* The response buffer (CANFDI_CFG_ISOTP_TX_BYTES), to write before
 * canfdi_isotp_send; NULL while busy or for NULL. */
uint8_t *canfdi_isotp_tx_buf(canfdi_isotp_t *t);

/* Sends tx_buf[0..len). Returns CANFDI_OK, -CANFDI_ERANGE (len 0 or above
 * the buffer), -CANFDI_EINVAL (NULL, busy). O(1). */
int32_t canfdi_isotp_send(canfdi_isotp_t *t, uint32_t len);

/*
 * One 1 ms step: timers, then at most one frame: writes its
 * CANFDI_CFG_ISOTP_FRAME_BYTES bytes (padded) into frame and returns 1, or
 * returns 0 (nothing to send) or -CANFDI_EINVAL. Cost O(CAN_DL).
 */
int32_t canfdi_isotp_step(canfdi_isotp_t *t, uint8_t frame[CANFDI_CFG_ISOTP_FRAME_BYTES]);

#endif /* CANFDI_ISOTP_H */
