/*
 * simprog.h: a G-code program as the simulator's run needs it (host only, sim_prog_*): the parsed blocks with
 * their blend tolerance, the machine functions (gcode.h events), and the programmed path (the X Y Z part of every
 * block, lines and arcs) with the deviation of a point from it.
 *
 * Two ways to hold it:
 *   whole     every block and path element in memory (about 350 bytes per block): what the VPOp reference, the
 *             runs that keep their setpoints (CSVs) and the benchmarks use;
 *   windowed  constant memory, for hours-long programs of millions of blocks (`lissom-sim run --no-csv`). The
 *             program is parsed twice: a first pass reads all of it (refused lines are counted and the first is
 *             reported, exactly as whole; the block count, length, end and last line are kept), then the run
 *             parses it again as it appends, one block ahead of the planner, and drops what lies behind: blocks
 *             before the one the planner took last, path elements behind the deviation check's reach (the caller
 *             says where, sim_prog_trim). The text is a buffer, or a file read in chunks (SIM_PROG_CHUNK).
 * Block indices and path element indices are absolute (from the program's start) in both.
 *
 * Deviation (sim_prog_deviation): the distance (X Y Z) from a point to the programmed path near the element of a
 * source line: every element whose span lies within reach_mm of that element's, and at least two whole arc-fit
 * runs (2 LSM_ARCFIT_MAX + 4 elements) before it, since a fitted arc carries the line of its last point and a
 * corner transition the line of the next block.
 *
 * Units: mm, rad (A B C). Memory: malloc (host).
 */
#ifndef LSM_SIM_PROG_H
#define LSM_SIM_PROG_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "gcode.h"
#include "geom.h"

/* Bytes read from a file at a time (windowed, from a file). */
#define SIM_PROG_CHUNK 65536

typedef struct sim_prog_block {
    lsm_gcode_block b;
    double tol_mm; /* blend tolerance: 0 exact stop */
} sim_prog_block;

/* A machine function of the program, where it comes among the blocks and when it ran (pathrun.h). */
typedef struct sim_run_mfunc {
    lsm_gcode_event ev;
    size_t before_block; /* index of the first program block after it (= blocks before it) */
    double t_s;          /* machine time when it ran (s); -1: not run (the VPOp reference runs no events) */
} sim_run_mfunc;

/* An element of the programmed path: a block's X Y Z geometry, where it starts along the path, its source line. */
typedef struct sim_prog_elem {
    lsm_geom g;
    double s0; /* cumulative length at its start (mm) */
    uint32_t line;
} sim_prog_elem;

typedef struct sim_prog {
    /* blocks [v0, n) are held, v[i - v0] */
    sim_prog_block *v;
    size_t v0, n, cap;
    /* path elements [e0, np) are held, path[i - e0] */
    sim_prog_elem *path;
    size_t e0, np, pcap;
    double s_next;     /* cumulative length at the end of the last element */
    sim_run_mfunc *ev; /* every machine function, in order */
    size_t n_ev, cap_ev;
    /* the whole program (after sim_prog_open) */
    size_t total;     /* motion blocks */
    size_t n_errors;  /* refused lines */
    double length_mm; /* programmed path length (X Y Z) */
    double start[LSM_MAX_AXES];
    double end[LSM_MAX_AXES];
    uint32_t last_line; /* source line of the last block */
    /* the parse */
    bool windowed;
    bool done;        /* every block is parsed */
    bool counting;    /* the first pass of a windowed program: nothing kept */
    const char *text; /* the text, or NULL: the file */
    size_t len, at;
    FILE *f;
    char *buf;
    size_t blen, bat;
    double blend_default_mm;
    uint8_t axis_mask;
    lsm_gcode *g;
    lsm_gcode_result *res;
    size_t held_max; /* most blocks + elements held at once */
} sim_prog;

/* Opens the program: text[len] if text != NULL, else the file at path. windowed: see above (the first pass runs
 * here). blend_default_mm: the machine's tolerance for G64 without P. Returns 0, or -1 with err set (a refused
 * line: "G-code line L column C: ..." and the count of the others; out of memory; the file unreadable). On error
 * the program is freed. */
int sim_prog_open(sim_prog *p, const char *text, size_t len, const char *path, bool windowed, uint8_t axis_mask,
                  double blend_default_mm, char *err, size_t errlen);

/* Parses on until block k is held or the program is done (windowed; whole: nothing to do). Returns 0, or -1 with
 * err set (out of memory, or the file changed between the passes). */
int sim_prog_need(sim_prog *p, size_t k, char *err, size_t errlen);

/* Block k (v0 <= k < n). */
static inline const sim_prog_block *sim_prog_block_at(const sim_prog *p, size_t k)
{
    return &p->v[k - p->v0];
}

/* Windowed: drops the blocks before keep_block and the path elements before keep_elem (amortised). */
void sim_prog_trim(sim_prog *p, size_t keep_block, size_t keep_elem);

/* Distance (X Y Z) from x to the programmed path near the element of source line `line` (above). *lo: the first
 * element it looked at (what a later point of a later line may still need). Returns -1 when the elements it
 * needs are no longer held (a windowed program trimmed too far: the caller's error). */
double sim_prog_deviation(const sim_prog *p, const double x[3], uint32_t line, double reach_mm, size_t *lo);

/* Distance (X Y Z) from x to one line or arc (helix: every turn) of the path, ends included. */
double sim_prog_distance(const lsm_geom *g, const double x[3]);

void sim_prog_free(sim_prog *p);

#endif /* LSM_SIM_PROG_H */
