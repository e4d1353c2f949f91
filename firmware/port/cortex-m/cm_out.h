/*
 * cm_out.h: a tiny text formatter for the Cortex-M images (strings, decimal and hex integers, fixed point),
 * written through semihosting. It replaces newlib's printf, which would link malloc, _sbrk and several KB of
 * stdio. Output is collected in a line buffer and written at each '\n' (one semihosting call per line).
 * Not reentrant: call it from the main loop only, never from the tick.
 */
#ifndef CM_OUT_H
#define CM_OUT_H

#include <stdint.h>

void cm_out_char(char c);
void cm_out_str(const char *s);
void cm_out_u32(uint32_t v);                        /* decimal, no padding */
void cm_out_i32(int32_t v);                         /* decimal with '-' for negatives */
void cm_out_hex32(uint32_t v);                      /* "0x" and exactly 8 lower-case hex digits */
void cm_out_fixed(int32_t v, unsigned frac_digits); /* v / 10^frac_digits, e.g. (12345, 2) -> "123.45" */
void cm_out_flush(void);                            /* write out a partial line */

#endif /* CM_OUT_H */
