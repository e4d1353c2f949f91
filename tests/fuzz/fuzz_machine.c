/*
 * fuzz_machine: the machine-file loader (host_sim/machine.c) and the strict JSON parser under it (json.c).
 *
 * Input: the file's bytes. Checks: the loader returns one of its status codes; on success every value is in the
 * range docs/machine_file.md documents (cycle in (0, 0.1], 1..6 axes with distinct names, every limit finite and
 * > 0, the axis mask matching the axes), and *m was written; on failure *m is untouched and the message is a
 * non-empty, NUL-terminated line. ASan / UBSan catch the rest (reads past the text, which is not NUL-terminated
 * here, overflows in number parsing, ...).
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "machine.h"

static void fail(const char *what, const char *err)
{
    fprintf(stderr, "FUZZ VIOLATION (machine): %s [%s]\n", what, err);
    abort();
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    /* an exact-size copy, not NUL-terminated: the loader must respect len */
    char *text = malloc(size ? size : 1);
    if (!text)
        return 0;
    if (size)
        memcpy(text, data, size);
    static sim_machine m;
    memset(&m, 0xA5, sizeof m);
    char err[300];
    memset(err, 'x', sizeof err);
    const sim_machine_status st = sim_machine_load_text(text, size, "fuzz.json", &m, err, sizeof err);
    free(text);
    if (st < SIM_MACHINE_E_DRIVE || st > SIM_MACHINE_OK)
        fail("status out of range", "");
    if (memchr(err, '\0', sizeof err) == NULL)
        fail("message not NUL-terminated", "");
    if (st != SIM_MACHINE_OK) {
        if (err[0] == '\0')
            fail("empty error message", err);
        const unsigned char *b = (const unsigned char *)&m;
        for (size_t i = 0; i < sizeof m; i++)
            if (b[i] != 0xA5)
                fail("the machine was written on failure", err);
        return 0;
    }
    if (!(m.cycle_s > 0 && m.cycle_s <= 0.1))
        fail("cycle out of range", err);
    if (m.n_axes < 1 || m.n_axes > SIM_MACHINE_MAX_AXES)
        fail("axis count out of range", err);
    if (!(m.lookahead_blocks >= 1) || !(m.blend_tol_mm >= 0) || !isfinite(m.blend_tol_mm))
        fail("look-ahead or blend tolerance out of range", err);
    if (memchr(m.name, '\0', sizeof m.name) == NULL || memchr(m.description, '\0', sizeof m.description) == NULL)
        fail("name or description not NUL-terminated", err);
    uint8_t mask = 0;
    for (int i = 0; i < m.n_axes; i++) {
        const sim_machine_axis *a = &m.axes[i];
        const double v[5] = {a->v_max_u_s, a->a_max_u_s2, a->j_max_u_s3, a->snap_max_u_s4, a->counts_per_u};
        for (int k = 0; k < 5; k++)
            if (!(isfinite(v[k]) && v[k] > 0))
                fail("a limit is not a finite number > 0", err);
        if (a->index < 0 || a->index > 5 || (mask & (1u << a->index)))
            fail("bad or repeated axis", err);
        if (a->rotary != (a->index >= 3))
            fail("rotary flag does not match the axis", err);
        mask |= (uint8_t)(1u << a->index);
    }
    if (mask != m.axis_mask)
        fail("axis mask does not match the axes", err);
    return 0;
}
