/* cm_out.c: see cm_out.h. */
#include "cm_out.h"

#include "cm_semihost.h"

#define CM_OUT_LINE 160

static char g_line[CM_OUT_LINE + 1];
static unsigned g_len;

void cm_out_flush(void)
{
    if (g_len == 0u)
        return;
    g_line[g_len] = '\0';
    cm_semihost_write0(g_line);
    g_len = 0u;
}

void cm_out_char(char c)
{
    g_line[g_len++] = c;
    if (c == '\n' || g_len == CM_OUT_LINE)
        cm_out_flush();
}

void cm_out_str(const char *s)
{
    while (*s != '\0')
        cm_out_char(*s++);
}

void cm_out_u32(uint32_t v)
{
    char digits[10];
    unsigned n = 0u;
    do {
        digits[n++] = (char)('0' + (char)(v % 10u));
        v /= 10u;
    } while (v != 0u);
    while (n > 0u)
        cm_out_char(digits[--n]);
}

void cm_out_i32(int32_t v)
{
    if (v < 0) {
        cm_out_char('-');
        cm_out_u32(0u - (uint32_t)v); /* exact also for INT32_MIN */
    } else {
        cm_out_u32((uint32_t)v);
    }
}

void cm_out_hex32(uint32_t v)
{
    static const char hex[] = "0123456789abcdef";
    cm_out_str("0x");
    for (int shift = 28; shift >= 0; shift -= 4)
        cm_out_char(hex[(v >> (unsigned)shift) & 0xFu]);
}

void cm_out_fixed(int32_t v, unsigned frac_digits)
{
    uint32_t mag = v < 0 ? 0u - (uint32_t)v : (uint32_t)v;
    uint32_t scale = 1u;
    for (unsigned i = 0u; i < frac_digits && i < 9u; i++)
        scale *= 10u;
    if (v < 0)
        cm_out_char('-');
    cm_out_u32(mag / scale);
    if (scale > 1u) {
        uint32_t frac = mag % scale;
        cm_out_char('.');
        for (uint32_t s = scale / 10u; s > 0u; s /= 10u) {
            cm_out_char((char)('0' + (char)(frac / s)));
            frac %= s;
        }
    }
}
