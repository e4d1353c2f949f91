/*
 * slcan.h: the serial-line CAN protocol (Lawicel "CAN232/CANUSB" ASCII protocol, "slcan") of common USB-CAN
 * adapters, seen from the adapter's side (lsm_slcan_*): a board whose CAN bus reaches the host through a UART
 * answers exactly like such an adapter, so python-can's `slcan` interface and Linux `slcand` talk to it
 * unchanged.
 *
 * Model. The host sends commands, one per line, each ended by CR (0x0D); the adapter answers every command
 * with CR (done) or BEL (0x07, refused), and sends every frame it receives from the bus as a line of its own.
 * Commands served (Lawicel CANUSB manual, rev. B):
 *     O            open the channel (frames pass both ways)            -> CR
 *     L            open listen-only (bus frames come up, none go down)  -> CR
 *     C            close the channel                                    -> CR
 *     Sn           bit rate n = 0..8 (10k .. 1M; kept, see below)       -> CR
 *     sxxyy        bit rate from SJA1000 BTR0/BTR1 (kept as given)       -> CR
 *     tiiildd..    send a standard frame: 3 hex id, dlc 0..8, 2 hex/byte -> z CR   (open only)
 *     Tiiiiiiiildd.. an extended frame: 8 hex id (29 bit)                -> Z CR   (open only)
 *     riiil        standard remote frame                                  -> z CR
 *     Riiiiiiiil   extended remote frame                                  -> Z CR
 *     V            version                                                -> V hhss CR (hardware, software)
 *     N            serial number                                          -> N xxxx CR
 *     F            status flags (bit 0 RX queue full, 1 TX queue full, 3 overrun) -> F hh CR
 *     Z0           time stamps off (the default; Z1, time stamps on, is refused)   -> CR
 *     Mxxxxxxxx, mxxxxxxxx  acceptance code / mask: accepted, no filtering is done -> CR
 *     CR alone     (hosts send it to flush the line)                    -> CR
 * Anything else (CAN FD lines d/D/b/B, polling P/A, unknown letters, bad hex, a dlc > 8, a line longer than
 * LSM_SLCAN_LINE_MAX) is answered with BEL and changes nothing. Bus frames go up as t/T/r/R lines without time
 * stamps: "t1818400000000" CR.
 * The bit rate is a property of the adapter's CAN controller: a board without a physical bus keeps the value
 * (lsm_slcan.bitrate_code) and does not use it.
 *
 * Contexts: one lsm_slcan belongs to one context (it is not shared); everything here is pure computation on
 * caller-owned memory (no allocation, no global state), so it may run in an interrupt or in the background. In the
 * controller application (ctl_app.h) the link's parser and encoder are the tick's: it parses the received lines and
 * sends the node's frames; SDO requests among them go to the background's SDO server through the node (canopen.h).
 * Units: none (characters, CAN identifiers).
 */
#ifndef LSM_SLCAN_H
#define LSM_SLCAN_H

#include "can.h"

#define LSM_SLCAN_LINE_MAX 32u  /* longest command line kept ("T" + 8 + 1 + 16 = 26 characters, + slack) */
#define LSM_SLCAN_REPLY_MAX 8u  /* longest reply to a command, CR included ("V1013" CR is 6) */
#define LSM_SLCAN_FRAME_MAX 27u /* longest frame line sent up, CR included ("T" + 8 + 1 + 16 + CR) */
#define LSM_SLCAN_CR '\r'
#define LSM_SLCAN_BEL '\a'

/* Status flags of the F command (Lawicel bits). */
#define LSM_SLCAN_F_RX_FULL 0x01u
#define LSM_SLCAN_F_TX_FULL 0x02u
#define LSM_SLCAN_F_OVERRUN 0x08u

typedef struct lsm_slcan {
    char line[LSM_SLCAN_LINE_MAX]; /* the command line being received (without its CR) */
    uint8_t len;                   /* characters in line */
    bool overlong;                 /* the present line is longer than LSM_SLCAN_LINE_MAX: refused at its CR */
    bool open;                     /* O or L received (and no C since) */
    bool listen_only;              /* opened with L */
    uint8_t bitrate_code;          /* last Sn (0..8), 0xFF after an s command; 8 (1 Mbit/s) at init */
    uint8_t status_flags;          /* LSM_SLCAN_F_*, set by the board, reported and cleared by F */
    uint32_t refused;              /* lines answered with BEL (wraps) */
    uint32_t frames_down;          /* frames taken from the host (wraps) */
} lsm_slcan;

typedef enum lsm_slcan_event {
    LSM_SLCAN_EV_NONE = 0,  /* nothing complete yet (the character was stored) */
    LSM_SLCAN_EV_REPLY = 1, /* a command line ended: send the reply */
    LSM_SLCAN_EV_FRAME = 2  /* a t/T/r/R line ended: *frame goes to the bus, and send the reply */
} lsm_slcan_event;

/* Closed channel, 1 Mbit/s, no line. Errors: LSM_E_NULL. Any context (before use). */
lsm_status lsm_slcan_init(lsm_slcan *s);

/*
 * Takes one character from the host. At the CR that ends a line it writes the reply (CR, z CR, Z CR, V.. CR,
 * N.. CR, F.. CR or BEL; NUL-terminated, at most LSM_SLCAN_REPLY_MAX characters plus the NUL) into reply and
 * returns LSM_SLCAN_EV_REPLY, or LSM_SLCAN_EV_FRAME with the frame to send in *frame. Line feeds (0x0A) and
 * NULs are ignored (terminals send CR LF). reply must hold LSM_SLCAN_REPLY_MAX + 1 characters; frame and reply
 * may not be NULL. The owner's context.
 */
lsm_slcan_event lsm_slcan_feed(lsm_slcan *s, char c, lsm_can_frame *frame, char *reply);

/*
 * Writes the line of a bus frame (t/T/r/R, upper-case hex, CR; NUL-terminated) into out, which holds
 * LSM_SLCAN_FRAME_MAX + 1 characters. Returns its length without the NUL, or 0 for a frame that cannot be
 * sent (dlc > 8, id out of its range). Any context.
 */
size_t lsm_slcan_encode(const lsm_can_frame *f, char *out);

#endif /* LSM_SLCAN_H */
