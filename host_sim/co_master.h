/*
 * co_master.h: a small CANopen master on Linux SocketCAN for `lissom-sim stream` (host only): raw CAN frames, an SDO
 * client (expedited upload, expedited and segmented download, CiA 301 §7.2.4), NMT, SYNC, and the frames the node
 * sends on its own (TPDOs, EMCY, heartbeat), which are handed to a callback while the client waits.
 *
 * One SDO transfer at a time; every call waits for its answer up to `sdo_timeout_ms` (default 1000 ms). Frames
 * that are not the awaited answer go to the `on_frame` callback (TPDO telemetry, EMCY), so no frame is lost while an
 * SDO transfer is pending.
 */
#ifndef LSM_SIM_CO_MASTER_H
#define LSM_SIM_CO_MASTER_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

typedef struct co_frame {
    uint32_t id;
    uint8_t len;
    uint8_t data[8];
} co_frame;

typedef void (*co_frame_fn)(void *ctx, const co_frame *f);

typedef struct co_master {
    int fd;
    uint8_t node_id;
    int sdo_timeout_ms;
    co_frame_fn on_frame;
    void *ctx;
    char err[256];
} co_master;

/* SDO results: 0 ok, > 0 the node's abort code, < 0 one of these. */
enum { CO_SDO_TIMEOUT = -1, CO_SDO_IO = -2, CO_SDO_PROTOCOL = -3 };

/* Opens the interface (vcan0, can0, slcan0, ...). 0 or -1 with m->err. */
int co_master_open(co_master *m, const char *iface, uint8_t node_id);
void co_master_close(co_master *m);

int co_send(co_master *m, uint32_t id, const uint8_t *data, uint8_t len);
/* Waits up to timeout_ms for frames and hands every one to on_frame. Returns the number handled or -1. */
int co_poll(co_master *m, int timeout_ms);

int co_nmt(co_master *m, uint8_t command); /* 0x01 start, 0x02 stop, 0x80 pre-op, 0x81 reset, 0x82 reset comm */
int co_sync(co_master *m);

/* SDO: see the result codes above. */
int64_t co_sdo_read(co_master *m, uint16_t index, uint8_t sub, uint32_t *value); /* expedited, up to 4 bytes */
int64_t co_sdo_write(co_master *m, uint16_t index, uint8_t sub, const uint8_t *data, size_t len);
int64_t co_sdo_write_u32(co_master *m, uint16_t index, uint8_t sub, uint32_t value, size_t len);

/* Text of an SDO abort code (CiA 301 table 22 and the node's path codes) or of a negative result. */
const char *co_sdo_abort_text(int64_t code);
/* Text of an EMCY error code (docs/canopen.md fault reactions), e.g. "E-stop". */
const char *co_emcy_text(uint16_t code);

#endif
