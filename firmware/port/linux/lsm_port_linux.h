/*
 * lsm_port_linux.h: the Linux port of Lissom (implements firmware/port/lsm_port.h) and its Linux-only extras.
 *
 * Model. One process, one thread. The port owns:
 *   - CAN: a SocketCAN raw socket (PF_CAN, SOCK_RAW, CAN_RAW) bound to any interface name (vcan0, can0,
 *     slcan0, ...), non-blocking. Classic frames only. Error frames are subscribed to (CAN_RAW_ERR_FILTER) and
 *     turned into bus events (error passive, bus-off, restarted / back to error active, controller overflow);
 *     frames the kernel dropped because the socket's receive queue was full (SO_RXQ_OVFL) become an RX-overrun
 *     event. A send that finds the socket queue full returns LSM_E_FULL (nothing queued); a send while the
 *     interface is down or bus-off returns LSM_E_PORT_IO.
 *   - the control tick: a timerfd on CLOCK_MONOTONIC with an absolute periodic deadline. lsm_port_idle()
 *     blocks in poll() until the timer expires (or a signal arrives) and then calls the tick function once;
 *     if the timer expired k > 1 times since the last tick, k - 1 ticks were missed: they are counted as
 *     overruns and not replayed (at most one pending tick, as lsm_port.h requires).
 *   - GPIO (libgpiod 1.6): one chip, up to three lines chosen by offset: the E-stop input, the drive-enable
 *     and in-position outputs. Each line is optional (-1 = not used). Outputs are requested inactive.
 *     The E-stop is read with the polarity given in the configuration; a read error, or an E-stop line that
 *     was configured but could not be requested, reads as "stop requested" (fail-safe). "No GPIO" mode (no
 *     chip): gpio_read returns LSM_E_PORT_UNSUPPORTED and gpio_write does nothing (LSM_E_PORT_UNSUPPORTED);
 *     the application then has no E-stop input and must say so.
 *   - the microsecond clock: CLOCK_MONOTONIC since lsm_port_init, modulo 2^32.
 *
 * Call lsm_port_linux_configure() before lsm_port_init(). Units: µs (`_us`).
 */
#ifndef LSM_PORT_LINUX_H
#define LSM_PORT_LINUX_H

#include "lsm_port.h"

typedef struct lsm_port_linux_config {
    const char *can_ifname; /* SocketCAN interface, e.g. "vcan0"; NULL = no CAN (send/recv: LSM_E_STATE) */
    const char *gpio_chip;  /* libgpiod chip: "gpiochip0", "/dev/gpiochip0", a label or a number; NULL = no GPIO */
    int estop_line;         /* line offsets on that chip, -1 = not used */
    int enable_line;
    int inpos_line;
    bool estop_active_low;   /* E-stop: physical 0 means "stop requested" (default: physical 1 means stop) */
    int estop_bias;          /* 0 as is, 1 pull-up, 2 pull-down, 3 bias disabled */
    bool outputs_active_low; /* drive-enable / in-position: physical 0 means "on" */
    const char *consumer;    /* libgpiod consumer label, NULL = "lissom-node" */
} lsm_port_linux_config;

/* What the CAN controller reported (from error frames) or the socket noticed. */
typedef enum lsm_port_bus_event {
    LSM_PORT_BUS_ERROR_ACTIVE = 0,  /* back to error active (CAN_ERR_CRTL_ACTIVE) */
    LSM_PORT_BUS_ERROR_PASSIVE = 1, /* RX or TX error passive (CAN_ERR_CRTL_RX/TX_PASSIVE) */
    LSM_PORT_BUS_OFF = 2,           /* CAN_ERR_BUSOFF */
    LSM_PORT_BUS_RESTARTED = 3,     /* CAN_ERR_RESTARTED: the controller left bus-off */
    LSM_PORT_BUS_RX_OVERRUN = 4     /* controller RX overflow, or frames dropped by the socket queue */
} lsm_port_bus_event;

/* Counters since lsm_port_init. */
typedef struct lsm_port_linux_stats {
    uint32_t rx_frames, tx_frames, tx_full, tx_errors, error_frames, rx_dropped, ticks, overruns;
    uint32_t tick_max_us; /* longest tick function run */
} lsm_port_linux_stats;

/* Sets what lsm_port_init opens. Copies the struct (the strings must outlive the port). Errors: LSM_E_NULL,
 * LSM_E_STATE (the port is already initialised). */
lsm_status lsm_port_linux_configure(const lsm_port_linux_config *cfg);

/* A configuration with no CAN, no GPIO, every line -1. */
lsm_port_linux_config lsm_port_linux_default_config(void);

/* Takes the oldest pending bus event. False when none. */
bool lsm_port_linux_bus_event(lsm_port_bus_event *ev);

/* True when lsm_port_init opened a GPIO chip (not "no GPIO" mode) and, for has_estop, an E-stop line. */
bool lsm_port_linux_has_gpio(void);
bool lsm_port_linux_has_estop(void);

/* Counters; NULL-safe. */
void lsm_port_linux_get_stats(lsm_port_linux_stats *out);

/* Makes a blocked lsm_port_idle() return at once (async-signal-safe: for SIGTERM handlers). */
void lsm_port_linux_wake(void);

/* Releases the socket, the timer and the GPIO lines (outputs inactive first). The port may be configured and
 * initialised again afterwards. */
void lsm_port_linux_close(void);

/* Text of the last OS error the port met (for messages), never NULL. */
const char *lsm_port_linux_last_error(void);

#endif /* LSM_PORT_LINUX_H */
