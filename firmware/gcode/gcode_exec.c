/*
 * gcode_exec.c: step 3 of a line (gcode.c): the word table executed on a copy of the modal state, in
 * LinuxCNC's order of execution, committed only if the whole line succeeds (gcode.h: the dialect).
 */
#include "gcode_int.h"

static lsm_real hypot_r(lsm_real a, lsm_real b)
{
    return lsm_sqrt(a * a + b * b);
}

/* The axes of an arc's plane (u, v) and its normal w, with the centre-offset letters along u and v and the one
 * that is not allowed (G17: I J, not K). */
typedef struct {
    int iu, iv, iw;
    char lu, lv, lbad;
} gc_arc_axes;

static gc_arc_axes arc_axes(lsm_gcode_plane plane)
{
    switch (plane) {
    case LSM_GCODE_PLANE_ZX: return (gc_arc_axes){LSM_GCODE_Z, LSM_GCODE_X, LSM_GCODE_Y, 'K', 'I', 'J'};
    case LSM_GCODE_PLANE_YZ: return (gc_arc_axes){LSM_GCODE_Y, LSM_GCODE_Z, LSM_GCODE_X, 'J', 'K', 'I'};
    case LSM_GCODE_PLANE_XY:
    default: return (gc_arc_axes){LSM_GCODE_X, LSM_GCODE_Y, LSM_GCODE_Z, 'I', 'J', 'K'};
    }
}

/* Stage 1: the arc's form (LinuxCNC: end words are optional in the centre form, whose end = start is a full
 * circle; the radius form needs an end word in its plane) and a feed. */
static lsm_status arc_check_form(const gc_words *w, const lsm_gcode_modal *m, const gc_arc_axes *ax, uint32_t mcol,
                                 lsm_gcode_result *res)
{
    const bool has_r = (w->seen & BIT('R')) != 0;
    const uint32_t ijk = w->seen & (BIT('I') | BIT('J') | BIT('K'));
    if (!has_r && !ijk)
        return fail_r(res, LSM_E_GC_ARC_FORM, mcol, "arc needs I J K (centre) or R (radius)");
    if (has_r && ijk) {
        uint32_t cr = w->col[LETTER('R')], ci = first_col(w, ijk);
        return fail_r(res, LSM_E_GC_ARC_FORM, cr > ci ? cr : ci, "arc with both R and I J K");
    }
    if (has_r && !(w->seen & (BIT(k_axis_letters[ax->iu]) | BIT(k_axis_letters[ax->iv]))))
        return fail_r(res, LSM_E_GC_ARC_FORM, mcol, "radius-form arc without an end word in its plane");
    if (ijk & BIT(ax->lbad))
        return fail_r(res, LSM_E_GC_ARC_FORM, w->col[LETTER(ax->lbad)], "centre offset off the arc's plane");
    if (m->feed_mm_s <= 0)
        return fail_r(res, LSM_E_GC_NO_FEED, mcol, "feed move with no feed (F) before");
    return LSM_OK;
}

/* Stage 2a: the centre of a radius-form arc (R, in the line's units); `same`: the end is the start. */
static lsm_status arc_centre_r(const gc_words *w, const gc_arc_axes *ax, const lsm_real s[LSM_GCODE_N_AXES],
                               const lsm_real e[LSM_GCODE_N_AXES], lsm_real lin, int dir, bool same, lsm_real c[2],
                               lsm_gcode_result *res)
{
    const lsm_real rtol = (lsm_real)LSM_GCODE_ARC_RADIUS_TOL_MM;
    const lsm_real du = e[ax->iu] - s[ax->iu], dv = e[ax->iv] - s[ax->iv];
    const lsm_real chord = hypot_r(du, dv);
    const lsm_real r = w->val[LETTER('R')] * lin;
    const lsm_real ar = lsm_fabs(r);
    const uint32_t rcol = w->col[LETTER('R')];
    if (same)
        return fail_r(res, LSM_E_GC_ARC_RADIUS, rcol, "radius-form arc ending on its start");
    if (ar < rtol)
        return fail_r(res, LSM_E_GC_ARC_RADIUS, rcol, "arc radius too small");
    lsm_real half = chord * LSM_R(0.5);
    if (half - ar > rtol)
        return fail_r(res, LSM_E_GC_ARC_RADIUS, rcol, "arc radius shorter than half the chord");
    lsm_real h2 = ar * ar - half * half;
    lsm_real h = h2 > 0 ? lsm_sqrt(h2) : LSM_R(0.0);
    /* the centre is left of the chord for a counter-clockwise arc of at most 180 degrees */
    lsm_real side = (lsm_real)(dir * (r > 0 ? 1 : -1));
    c[0] = s[ax->iu] + LSM_R(0.5) * du + side * h * (-dv / chord);
    c[1] = s[ax->iv] + LSM_R(0.5) * dv + side * h * (du / chord);
    return LSM_OK;
}

/* Stage 2b: the centre of a centre-form arc (I J K, relative, or absolute under G90.1), and the check that start
 * and end lie on one circle (LinuxCNC's tolerances). */
static lsm_status arc_centre_ijk(const gc_words *w, const lsm_gcode_modal *m, const gc_arc_axes *ax,
                                 const lsm_real s[LSM_GCODE_N_AXES], const lsm_real e[LSM_GCODE_N_AXES],
                                 const lsm_real off[LSM_GCODE_N_AXES], lsm_real lin, uint32_t mcol, lsm_real c[2],
                                 lsm_gcode_result *res)
{
    const int iu = ax->iu, iv = ax->iv;
    const char lu = ax->lu, lv = ax->lv;
    const uint32_t ijk = w->seen & (BIT('I') | BIT('J') | BIT('K'));
    lsm_real ou = (w->seen & BIT(lu)) ? w->val[LETTER(lu)] * lin : LSM_R(0.0);
    lsm_real ov = (w->seen & BIT(lv)) ? w->val[LETTER(lv)] * lin : LSM_R(0.0);
    if (m->arc_absolute) { /* G90.1: program coordinates of the centre (a missing one: the start's) */
        c[0] = (w->seen & BIT(lu)) ? ou + off[iu] : s[iu];
        c[1] = (w->seen & BIT(lv)) ? ov + off[iv] : s[iv];
    } else {
        c[0] = s[iu] + ou;
        c[1] = s[iv] + ov;
    }
    const lsm_real rtol = (lsm_real)LSM_GCODE_ARC_RADIUS_TOL_MM;
    lsm_real r1 = hypot_r(s[iu] - c[0], s[iv] - c[1]);
    lsm_real r2 = hypot_r(e[iu] - c[0], e[iv] - c[1]);
    if (r1 < rtol || r2 < rtol)
        return fail_r(res, LSM_E_GC_ARC_CENTRE, first_col(w, ijk), "arc centre on its start or end point");
    lsm_real err = lsm_fabs(r1 - r2);
    lsm_real rmax = r1 > r2 ? r1 : r2;
    if (err > (lsm_real)LSM_GCODE_ARC_ABS_TOL_MM || err > (lsm_real)LSM_GCODE_ARC_REL_TOL * rmax)
        return fail_r(res, LSM_E_GC_ARC_MISMATCH, mcol, "arc start and end radii differ");
    return LSM_OK;
}

/* Stage 3: the block, from the centre (cu, cv): the swept angle (a full turn when the end is the start) plus the
 * extra turns (P). */
static void arc_fill(const lsm_gcode_modal *m, const gc_arc_axes *ax, const lsm_real s[LSM_GCODE_N_AXES],
                     const lsm_real e[LSM_GCODE_N_AXES], int dir, bool same, uint32_t turns, const lsm_real c[2],
                     lsm_gcode_block *b)
{
    const int iu = ax->iu, iv = ax->iv, iw = ax->iw;
    const lsm_real cu = c[0], cv = c[1];
    lsm_real ts = lsm_atan2(s[iv] - cv, s[iu] - cu);
    lsm_real te = lsm_atan2(e[iv] - cv, e[iu] - cu);
    lsm_real d = dir > 0 ? te - ts : ts - te;
    if (same) {
        d = 2 * GC_PI;
    } else {
        while (d <= 0)
            d += 2 * GC_PI;
        while (d > 2 * GC_PI)
            d -= 2 * GC_PI;
    }
    b->type = LSM_GCODE_BLOCK_ARC;
    b->plane = m->plane;
    b->dir = (int8_t)dir;
    b->turns = turns - 1u;
    b->centre[iu] = cu;
    b->centre[iv] = cv;
    b->centre[iw] = s[iw];
    b->radius_mm = hypot_r(s[iu] - cu, s[iv] - cv);
    b->radius_end_mm = hypot_r(e[iu] - cu, e[iv] - cv);
    b->angle_rad = d + 2 * GC_PI * (lsm_real)(turns - 1u);
    b->helix_mm = e[iw] - s[iw];
}

/* Arc geometry in the plane (u, v) with normal w: form, centre, block. */
static lsm_status make_arc(const gc_words *w, const lsm_gcode_modal *m, const lsm_real s[LSM_GCODE_N_AXES],
                           const lsm_real e[LSM_GCODE_N_AXES], const lsm_real off[LSM_GCODE_N_AXES], lsm_real lin,
                           uint32_t turns, uint32_t mcol, lsm_gcode_block *b, lsm_gcode_result *res)
{
    const gc_arc_axes ax = arc_axes(m->plane);
    lsm_status st = arc_check_form(w, m, &ax, mcol, res);
    if (st != LSM_OK)
        return st;
    const int dir = m->motion == LSM_GCODE_MOTION_CCW ? 1 : -1;
    /* same-point threshold: a few ulps of the coordinates */
    const lsm_real scale = LSM_R(1.0) + lsm_fabs(s[ax.iu]) + lsm_fabs(s[ax.iv]);
    const lsm_real same_eps = scale * (LSM_REAL_IS_FLOAT ? (lsm_real)4e-7 : (lsm_real)1e-12);
    const bool same = hypot_r(e[ax.iu] - s[ax.iu], e[ax.iv] - s[ax.iv]) <= same_eps;
    lsm_real c[2];
    if (w->seen & BIT('R'))
        st = arc_centre_r(w, &ax, s, e, lin, dir, same, c, res);
    else
        st = arc_centre_ijk(w, m, &ax, s, e, off, lin, mcol, c, res);
    if (st != LSM_OK)
        return st;
    arc_fill(m, &ax, s, e, dir, same, turns, c, b);
    return LSM_OK;
}

/* Step 3: execute the word table on a copy of the state, in LinuxCNC's order of execution; commit on
 * success. */

/* Offsets that a line may change (committed with the modal state). */
typedef struct {
    lsm_real wcs[LSM_GCODE_N_WCS][LSM_GCODE_N_AXES];
    lsm_real g92[LSM_GCODE_N_AXES];
    lsm_real home[2][LSM_GCODE_N_AXES];
} gc_offsets;

typedef struct {
    lsm_gcode_modal m;
    gc_offsets o;
    lsm_real lin;                   /* mm per G-code length unit on this line */
    lsm_real end[LSM_GCODE_N_AXES]; /* where the line's motion ends (machine coordinates) */
} gc_exec;


/* Offset from program to machine coordinates of axis k (work offset in use plus G92). */
static lsm_real offset_of(const gc_exec *x, int k)
{
    return x->o.wcs[x->m.wcs - 1][k] + x->o.g92[k];
}

/* The value of axis word k in mm (X Y Z) or rad (A B C). */
static lsm_real axis_value(const gc_words *w, const gc_exec *x, int k)
{
    return w->val[LETTER(k_axis_letters[k])] * (k >= LSM_GCODE_A ? GC_DEG2RAD : x->lin);
}

/* Units, F and S, then the machine functions before the motion: S, T, M6, M3-M5, M7-M9, G4. */
static lsm_status exec_functions(const gc_words *w, gc_exec *x, lsm_gcode_result *res)
{
    lsm_gcode_modal *m = &x->m;
    /* units first: every number on the line is read in the line's final units */
    if (w->g[GRP_UNITS] >= 0)
        m->units = w->g[GRP_UNITS] == 200 ? LSM_GCODE_UNITS_INCH : LSM_GCODE_UNITS_MM;
    x->lin = m->units == LSM_GCODE_UNITS_INCH ? GC_MM_PER_INCH : LSM_R(1.0);
    if (w->seen & BIT('F')) {
        lsm_real f = w->val[LETTER('F')];
        m->feed_mm_s = f * x->lin / LSM_R(60.0);
        m->feed_rot_rad_s = f / LSM_R(60.0) * GC_DEG2RAD;
    }
    if (w->seen & BIT('S')) {
        m->speed_rpm = w->val[LETTER('S')];
        push_event(res, LSM_GCODE_EV_SPINDLE_SPEED, true, 0, m->speed_rpm);
    }
    if (w->seen & BIT('T')) {
        m->tool_selected = (int32_t)w->val[LETTER('T')];
        push_event(res, LSM_GCODE_EV_TOOL_SELECT, false, m->tool_selected, 0);
    }
    if (w->m[MG_TOOL] >= 0) {
        m->tool_loaded = m->tool_selected >= 0 ? m->tool_selected : 0;
        push_event(res, LSM_GCODE_EV_TOOL_CHANGE, true, m->tool_loaded, 0);
    }
    if (w->m[MG_SPINDLE] >= 0) {
        const int16_t c = w->m[MG_SPINDLE];
        m->spindle = (uint8_t)(c / 10);
        push_event(res,
                   c == 30   ? LSM_GCODE_EV_SPINDLE_CW
                   : c == 40 ? LSM_GCODE_EV_SPINDLE_CCW
                             : LSM_GCODE_EV_SPINDLE_STOP,
                   true, 0, c == 50 ? LSM_R(0.0) : m->speed_rpm);
    }
    if (w->m[MG_MIST] >= 0) {
        m->mist = true;
        push_event(res, LSM_GCODE_EV_COOLANT_MIST, true, 0, 0);
    }
    if (w->m[MG_FLOOD] >= 0) {
        m->flood = true;
        push_event(res, LSM_GCODE_EV_COOLANT_FLOOD, true, 0, 0);
    }
    if (w->m[MG_COOL_OFF] >= 0) {
        m->mist = m->flood = false;
        push_event(res, LSM_GCODE_EV_COOLANT_OFF, true, 0, 0);
    }
    if (w->g[GRP_NONMODAL] == 40) {
        if (!(w->seen & BIT('P')))
            return fail_r(res, LSM_E_GC_MISSING_ARG, w->gcol[GRP_NONMODAL], "G4 needs P (seconds)");
        const lsm_real t = w->val[LETTER('P')];
        if (t < 0)
            return fail_r(res, LSM_E_GC_BAD_VALUE, w->col[LETTER('P')], "negative dwell");
        push_event(res, LSM_GCODE_EV_DWELL, true, 0, t);
    }
    return LSM_OK;
}

/* Plane, distance modes, tool length offset, work offset selection, path control and motion mode. */
static lsm_status exec_modes(const gc_words *w, gc_exec *x, lsm_gcode_result *res)
{
    lsm_gcode_modal *m = &x->m;
    if (w->g[GRP_PLANE] >= 0)
        m->plane = (lsm_gcode_plane)(w->g[GRP_PLANE] / 10);
    if (w->g[GRP_DISTANCE] >= 0)
        m->distance = w->g[GRP_DISTANCE] == 900 ? LSM_GCODE_ABSOLUTE : LSM_GCODE_INCREMENTAL;
    if (w->g[GRP_ARCDIST] >= 0)
        m->arc_absolute = w->g[GRP_ARCDIST] == 901;
    if (w->g[GRP_TOOL_LEN] == 430) {
        m->tool_length_on = true;
        m->tool_length_h = (w->seen & BIT('H')) ? (int32_t)w->val[LETTER('H')] : m->tool_loaded;
        push_event(res, LSM_GCODE_EV_TOOL_LENGTH, false, m->tool_length_h, 0);
    } else if (w->g[GRP_TOOL_LEN] == 490) {
        m->tool_length_on = false;
        m->tool_length_h = -1;
        push_event(res, LSM_GCODE_EV_TOOL_LENGTH_OFF, false, 0, 0);
    }
    if ((w->seen & BIT('H')) && w->g[GRP_TOOL_LEN] != 430)
        return fail_r(res, LSM_E_GC_UNUSED_WORD, w->col[LETTER('H')], "H without G43");
    if (w->g[GRP_WCS] >= 0)
        m->wcs = (uint8_t)((w->g[GRP_WCS] - 530) / 10);
    if (w->g[GRP_PATH] == 610) {
        m->blend = LSM_GCODE_EXACT_STOP;
        m->blend_tol_mm = 0;
    }
    if (w->g[GRP_MOTION] >= 0) {
        switch (w->g[GRP_MOTION]) {
        case 0: m->motion = LSM_GCODE_MOTION_RAPID; break;
        case 10: m->motion = LSM_GCODE_MOTION_LINEAR; break;
        case 20: m->motion = LSM_GCODE_MOTION_CW; break;
        case 30: m->motion = LSM_GCODE_MOTION_CCW; break;
        default: m->motion = LSM_GCODE_MOTION_NONE; break;
        }
    }
    return LSM_OK;
}

/* Who uses P on this line: G4, G10, G64 or an arc's turns; more than one is an error. */
static lsm_status exec_p(const gc_words *w, gc_exec *x, bool arc_cmd, uint32_t *turns, lsm_gcode_result *res)
{
    const bool g64 = w->g[GRP_PATH] == 640;
    const int16_t nm = w->g[GRP_NONMODAL];
    const uint32_t pcol = w->col[LETTER('P')];
    *turns = 1;
    if (w->seen & BIT('P')) {
        if (g64 && arc_cmd)
            return fail_r(res, LSM_E_GC_ARC_FORM, pcol, "P of both G64 and an arc");
        const int users = (int)g64 + (int)arc_cmd + (int)(nm == 40) + (int)(nm == 100);
        if (users == 0)
            return fail_r(res, LSM_E_GC_UNUSED_WORD, pcol, "P without G4, G10, G64 or an arc");
        if (users > 1)
            return fail_r(res, LSM_E_GC_MODAL_CONFLICT, pcol, "P used by two commands");
        if (arc_cmd) {
            if (!as_uint(&w->pnum, turns) || *turns < 1 || *turns > LSM_GCODE_MAX_TURNS)
                return fail_r(res, LSM_E_GC_BAD_VALUE, pcol, "arc turns P must be an integer 1..1000");
        } else if (g64 && w->val[LETTER('P')] < 0) {
            return fail_r(res, LSM_E_GC_BAD_VALUE, pcol, "negative blend tolerance");
        }
    }
    if (g64) {
        x->m.blend = LSM_GCODE_BLEND;
        x->m.blend_tol_mm = (w->seen & BIT('P')) ? w->val[LETTER('P')] * x->lin : LSM_R(0.0);
    }
    return LSM_OK;
}

/* G10 L2 / L20: set the origin of work offset P (0: the one in use). Values are absolute machine
 * coordinates (L2) or make the current point have these coordinates (L20), in G90 and G91 alike. */
static lsm_status exec_g10(const lsm_gcode *p, const gc_words *w, gc_exec *x, lsm_gcode_result *res)
{
    const uint32_t col = w->gcol[GRP_NONMODAL];
    uint32_t l = 0, sys = 0;
    if (!(w->seen & BIT('L')))
        return fail_r(res, LSM_E_GC_MISSING_ARG, col, "G10 needs L2 or L20");
    if (!as_uint(&w->lnum, &l) || (l != 2 && l != 20)) {
        const bool tool = l == 1 || l == 10 || l == 11;
        return fail_r(res, tool ? LSM_E_GC_UNSUPPORTED : LSM_E_GC_BAD_VALUE, w->col[LETTER('L')],
                      tool ? "unsupported: tool table (G10 L1/L10/L11)" : "G10 needs L2 or L20");
    }
    if (!(w->seen & BIT('P')))
        return fail_r(res, LSM_E_GC_MISSING_ARG, col, "G10 needs P (coordinate system 0..6)");
    if (!as_uint(&w->pnum, &sys) || sys > 9)
        return fail_r(res, LSM_E_GC_BAD_VALUE, w->col[LETTER('P')], "coordinate system P must be 0..9");
    if (sys > LSM_GCODE_N_WCS)
        return fail_r(res, LSM_E_GC_UNSUPPORTED, w->col[LETTER('P')], "unsupported: coordinate systems G59.1-G59.3");
    if (w->seen & BIT('R'))
        return fail_r(res, LSM_E_GC_UNSUPPORTED, w->col[LETTER('R')], "unsupported: coordinate system rotation (R)");
    const unsigned idx = sys == 0 ? (unsigned)x->m.wcs - 1u : sys - 1u;
    for (int k = 0; k < LSM_GCODE_N_AXES; k++) {
        if (!(w->seen & BIT(k_axis_letters[k])))
            continue;
        const lsm_real v = axis_value(w, x, k);
        x->o.wcs[idx][k] = l == 2 ? v : p->pos[k] - x->o.g92[k] - v;
    }
    return LSM_OK;
}

/* G92 (the current point gets the given coordinates), G92.1 / G92.2 (offsets cleared). */
static lsm_status exec_g92(const lsm_gcode *p, const gc_words *w, gc_exec *x, lsm_gcode_result *res)
{
    if (w->g[GRP_NONMODAL] != 920) {
        for (int k = 0; k < LSM_GCODE_N_AXES; k++)
            x->o.g92[k] = 0;
        return LSM_OK;
    }
    if (!(w->seen & AXIS_BITS))
        return fail_r(res, LSM_E_GC_MISSING_ARG, w->gcol[GRP_NONMODAL], "G92 needs at least one axis word");
    for (int k = 0; k < LSM_GCODE_N_AXES; k++)
        if (w->seen & BIT(k_axis_letters[k]))
            x->o.g92[k] = p->pos[k] - x->o.wcs[x->m.wcs - 1][k] - axis_value(w, x, k);
    return LSM_OK;
}

/* End point of the axis words as a move (G0-G3, G28/G30 intermediate point); G53: machine coordinates. */
static lsm_status exec_end(const lsm_gcode *p, const gc_words *w, gc_exec *x, bool g53, lsm_gcode_result *res)
{
    for (int k = 0; k < LSM_GCODE_N_AXES; k++) {
        char L = k_axis_letters[k];
        x->end[k] = p->pos[k];
        if (!(w->seen & BIT(L)))
            continue;
        const bool rotary = k >= LSM_GCODE_A;
        const lsm_real v = axis_value(w, x, k);
        if (x->m.distance == LSM_GCODE_INCREMENTAL) {
            x->end[k] = p->pos[k] + v;
        } else {
            const lsm_real off = g53 ? LSM_R(0.0) : offset_of(x, k);
            x->end[k] = off != 0 ? v + off : v;
        }
        lsm_real lim = (lsm_real)LSM_GCODE_MAX_ABS * (rotary ? GC_DEG2RAD : LSM_R(1.0));
        if (lsm_fabs(x->end[k]) > lim)
            return fail_r(res, LSM_E_GC_NUMBER_RANGE, w->col[LETTER(L)], "coordinate out of range");
    }
    return LSM_OK;
}

/* Appends a straight block from `from` to `to` unless they are equal. */
static void emit_line(lsm_gcode_result *res, lsm_gcode_block_type type, const lsm_real from[LSM_GCODE_N_AXES],
                      const lsm_real to[LSM_GCODE_N_AXES], const lsm_gcode_modal *m)
{
    bool moves = false;
    for (int k = 0; k < LSM_GCODE_N_AXES; k++)
        if (to[k] != from[k])
            moves = true;
    if (!moves || res->n_blocks >= LSM_GCODE_MAX_BLOCKS)
        return;
    lsm_gcode_block b = {0};
    b.type = type;
    b.line = res->line;
    for (int k = 0; k < LSM_GCODE_N_AXES; k++) {
        b.start[k] = from[k];
        b.end[k] = to[k];
    }
    if (type != LSM_GCODE_BLOCK_RAPID) {
        b.feed_mm_s = m->feed_mm_s;
        b.feed_rot_rad_s = m->feed_rot_rad_s;
    }
    res->blocks[res->n_blocks++] = b;
}

/* G28 / G30: rapid to the intermediate point of the axis words, then the given axes (all without
 * axis words) rapid to the stored position. */
static void exec_home(const lsm_gcode *p, const gc_words *w, gc_exec *x, lsm_gcode_result *res)
{
    const lsm_real *home = x->o.home[w->g[GRP_NONMODAL] == 300 ? 1 : 0];
    const bool any = (w->seen & AXIS_BITS) != 0;
    lsm_real fin[LSM_GCODE_N_AXES];
    for (int k = 0; k < LSM_GCODE_N_AXES; k++) {
        const bool present = (p->opt.axis_mask & (1u << k)) != 0;
        fin[k] = present && (!any || (w->seen & BIT(k_axis_letters[k]))) ? home[k] : x->end[k];
    }
    emit_line(res, LSM_GCODE_BLOCK_RAPID, p->pos, x->end, &x->m);
    emit_line(res, LSM_GCODE_BLOCK_RAPID, x->end, fin, &x->m);
    for (int k = 0; k < LSM_GCODE_N_AXES; k++)
        x->end[k] = fin[k];
}

/* Non-modal commands that use axis words, and G28.1 / G30.1. Returns through *moved whether the line's axis
 * words were consumed. */
static lsm_status exec_nonmodal(const lsm_gcode *p, const gc_words *w, gc_exec *x, bool *used_axes,
                                lsm_gcode_result *res)
{
    const int16_t nm = w->g[GRP_NONMODAL];
    const bool has_axis = (w->seen & AXIS_BITS) != 0;
    *used_axes = nm == 100 || nm == 280 || nm == 300 || nm == 920;
    if (*used_axes && has_axis && w->g[GRP_MOTION] >= 0 && w->g[GRP_MOTION] != 800)
        return fail_r(res, LSM_E_GC_MODAL_CONFLICT, w->gcol[GRP_MOTION], "two commands use the axis words");
    if ((w->seen & BIT('L')) && nm != 100)
        return fail_r(res, LSM_E_GC_UNUSED_WORD, w->col[LETTER('L')], "L without G10");
    if ((nm == 281 || nm == 301 || nm == 921 || nm == 922) && has_axis)
        return fail_r(res, LSM_E_GC_UNUSED_WORD, first_col(w, AXIS_BITS), "axis words with G28.1, G30.1 or G92.1");
    switch (nm) {
    case 100: return exec_g10(p, w, x, res);
    case 920:
    case 921:
    case 922: return exec_g92(p, w, x, res);
    case 281:
    case 301:
        for (int k = 0; k < LSM_GCODE_N_AXES; k++)
            x->o.home[nm == 301 ? 1 : 0][k] = p->pos[k];
        return LSM_OK;
    case 280:
    case 300: {
        lsm_status st = exec_end(p, w, x, false, res);
        if (st != LSM_OK)
            return st;
        exec_home(p, w, x, res);
        return LSM_OK;
    }
    default: return LSM_OK;
    }
}

/* The motion of the line (G0-G3 with the modal motion mode). */
static lsm_status exec_motion(const lsm_gcode *p, const gc_words *w, gc_exec *x, uint32_t turns, lsm_gcode_result *res)
{
    const lsm_gcode_modal *m = &x->m;
    const bool explicit_motion = w->g[GRP_MOTION] >= 0;
    const bool has_axis = (w->seen & AXIS_BITS) != 0;
    const bool is_arc_mode = m->motion == LSM_GCODE_MOTION_CW || m->motion == LSM_GCODE_MOTION_CCW;
    const bool g53 = w->g[GRP_NONMODAL] == 530;
    const uint32_t mcol = explicit_motion ? w->gcol[GRP_MOTION] : first_col(w, AXIS_BITS);
    if (g53 && (is_arc_mode || m->motion == LSM_GCODE_MOTION_NONE))
        return fail_r(res, LSM_E_GC_UNUSED_WORD, w->gcol[GRP_NONMODAL], "G53 needs G0 or G1");
    if (g53 && m->distance == LSM_GCODE_INCREMENTAL)
        return fail_r(res, LSM_E_GC_BAD_VALUE, w->gcol[GRP_NONMODAL], "G53 in incremental mode (G91)");
    lsm_status st = exec_end(p, w, x, g53, res);
    if (st != LSM_OK)
        return st;
    if (is_arc_mode && (explicit_motion || has_axis)) {
        lsm_gcode_block b = {0};
        lsm_real off[LSM_GCODE_N_AXES];
        for (int k = 0; k < LSM_GCODE_N_AXES; k++)
            off[k] = offset_of(x, k);
        st = make_arc(w, m, p->pos, x->end, off, x->lin, turns, mcol, &b, res);
        if (st != LSM_OK)
            return st;
        b.line = res->line;
        for (int k = 0; k < LSM_GCODE_N_AXES; k++) {
            b.start[k] = p->pos[k];
            b.end[k] = x->end[k];
        }
        b.feed_mm_s = m->feed_mm_s;
        b.feed_rot_rad_s = m->feed_rot_rad_s;
        res->blocks[res->n_blocks++] = b;
    } else if ((m->motion == LSM_GCODE_MOTION_RAPID || m->motion == LSM_GCODE_MOTION_LINEAR) && has_axis) {
        if (m->motion == LSM_GCODE_MOTION_LINEAR && m->feed_mm_s <= 0)
            return fail_r(res, LSM_E_GC_NO_FEED, mcol, "feed move with no feed (F) before");
        emit_line(res, m->motion == LSM_GCODE_MOTION_RAPID ? LSM_GCODE_BLOCK_RAPID : LSM_GCODE_BLOCK_LINEAR, p->pos,
                  x->end, m);
    }
    return LSM_OK;
}

/* After the motion: M0 / M1, M2 / M30 (which also stop the spindle and the coolant, as in LinuxCNC). */
static void exec_stop(const lsm_gcode *p, const gc_words *w, gc_exec *x, lsm_gcode_result *res)
{
    const int16_t c = w->m[MG_STOP];
    if (c == 0)
        push_event(res, LSM_GCODE_EV_PAUSE, true, 0, 0);
    else if (c == 10 && p->opt.optional_stop)
        push_event(res, LSM_GCODE_EV_OPTIONAL_PAUSE, true, 0, 0);
    else if (c == 20 || c == 300) {
        if (x->m.spindle != 5)
            push_event(res, LSM_GCODE_EV_SPINDLE_STOP, true, 0, 0);
        if (x->m.mist || x->m.flood)
            push_event(res, LSM_GCODE_EV_COOLANT_OFF, true, 0, 0);
        x->m.spindle = 5;
        x->m.mist = x->m.flood = false;
        push_event(res, LSM_GCODE_EV_END, true, c / 10, 0);
    }
}

lsm_status lsm_gc_execute(lsm_gcode *p, const gc_words *w, lsm_gcode_result *res)
{
    gc_exec x;
    x.m = p->modal;
    for (int s = 0; s < LSM_GCODE_N_WCS; s++)
        for (int k = 0; k < LSM_GCODE_N_AXES; k++)
            x.o.wcs[s][k] = p->wcs[s][k];
    for (int k = 0; k < LSM_GCODE_N_AXES; k++) {
        x.o.g92[k] = p->g92[k];
        x.o.home[0][k] = p->home[0][k];
        x.o.home[1][k] = p->home[1][k];
        x.end[k] = p->pos[k];
    }
    lsm_status st = exec_functions(w, &x, res);
    if (st == LSM_OK)
        st = exec_modes(w, &x, res);
    if (st != LSM_OK)
        return st;
    const bool has_axis = (w->seen & AXIS_BITS) != 0;
    const int16_t nm = w->g[GRP_NONMODAL];
    const bool nm_axes = nm == 100 || nm == 280 || nm == 300 || nm == 920;
    const bool is_arc_mode = x.m.motion == LSM_GCODE_MOTION_CW || x.m.motion == LSM_GCODE_MOTION_CCW;
    const bool arc_cmd = !nm_axes && is_arc_mode && (w->g[GRP_MOTION] >= 0 || has_axis);
    if (has_axis && !nm_axes && x.m.motion == LSM_GCODE_MOTION_NONE)
        return fail_r(res, LSM_E_GC_UNUSED_WORD, first_col(w, AXIS_BITS), "axis words without a motion mode (G80)");
    if ((w->seen & ARC_BITS) && !arc_cmd) {
        const bool g10_r = nm == 100 && (w->seen & ARC_BITS) == BIT('R');
        if (!g10_r)
            return fail_r(res, LSM_E_GC_UNUSED_WORD, first_col(w, ARC_BITS), "I J K R without G2 or G3");
    }
    uint32_t turns;
    st = exec_p(w, &x, arc_cmd, &turns, res);
    if (st != LSM_OK)
        return st;
    bool used_axes;
    st = exec_nonmodal(p, w, &x, &used_axes, res);
    if (st == LSM_OK && !used_axes)
        st = exec_motion(p, w, &x, turns, res);
    if (st != LSM_OK)
        return st;
    exec_stop(p, w, &x, res);
    res->nonmodal = w->g[GRP_NONMODAL];

    /* commit */
    p->modal = x.m;
    for (int s = 0; s < LSM_GCODE_N_WCS; s++)
        for (int k = 0; k < LSM_GCODE_N_AXES; k++)
            p->wcs[s][k] = x.o.wcs[s][k];
    for (int k = 0; k < LSM_GCODE_N_AXES; k++) {
        p->g92[k] = x.o.g92[k];
        p->home[0][k] = x.o.home[0][k];
        p->home[1][k] = x.o.home[1][k];
        p->pos[k] = x.end[k];
    }
    if (w->m[MG_STOP] == 20 || w->m[MG_STOP] == 300)
        p->ended = true;
    return LSM_OK;
}
