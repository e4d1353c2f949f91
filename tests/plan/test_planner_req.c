/*
 * test_planner_req.c: the requests the control cycle (tick) posts to the planner, which the background applies
 * (planner.h, lsm_planner_req; lsm_atomic.h):
 *   - a posted release counts at once in lsm_planner_free / count / block and frees the slots when applied;
 *     an earlier id frees nothing more; beyond the tail it stops at the tail;
 *   - a posted horizon changes nothing until applied, then sets the horizon as lsm_planner_set_horizon would,
 *     including commit_dirty when the end moved in any of the posts since the last apply; a posted cursor
 *     (lsm_planner_post_cursor) moves the horizon's point and speed and keeps its end (not dirty);
 *   - the stale acknowledgement: a piece planned before an invalidation stays stale after its ack;
 *   - with LSM_TEST_THREADS (the ThreadSanitizer build, ctest planner_req_tsan): the tick posts from one thread
 *     (whole horizons and cursors) while the background applies from another; every applied horizon is one whole
 *     post (no torn tuple; a cursor's end is the last whole post's), the
 *     horizon and the head only move forward, and the last post is what is applied at the end. Clean under
 *     -fsanitize=thread: no data race in the hand-off.
 * Built double and float (the values compared are exact in both).
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "planner.h"

#define CAP 16u
static lsm_pblock g_blk[CAP];
static lsm_planner g_pl;

/* A planner holding n lines of a staircase (1 mm steps in X and Y, exact stops at the corners). */
static uint32_t setup_lines(unsigned n)
{
    lsm_planner_config cfg;
    lsm_planner_default_config(&cfg);
    const lsm_real start[LSM_MAX_AXES] = {0};
    assert_int_equal(lsm_planner_init(&g_pl, &cfg, g_blk, CAP, start), LSM_OK);
    lsm_planner_move mv;
    memset(&mv, 0, sizeof mv);
    mv.feed_mm_s = 50;
    mv.tol_mm = 0;
    for (unsigned i = 1; i <= n; i++) {
        lsm_real end[LSM_MAX_AXES] = {0};
        end[0] = (lsm_real)((i + 1u) / 2u);
        end[1] = (lsm_real)(i / 2u);
        mv.seq = i;
        assert_int_equal(lsm_planner_append_line(&g_pl, end, &mv), LSM_OK);
    }
    (void)lsm_planner_flush(&g_pl);
    return lsm_planner_count(&g_pl);
}

static void test_release(void **state)
{
    (void)state;
    const uint32_t n = setup_lines(6);
    assert_true(n >= 4u);
    const uint32_t h0 = g_pl.head;
    lsm_planner_post_release(&g_pl, h0 + 2u);
    assert_int_equal(g_pl.head, h0); /* nothing of the planner's is written by the tick */
    assert_int_equal(lsm_planner_count(&g_pl), n - 2u);
    assert_int_equal(lsm_planner_free(&g_pl), CAP - (n - 2u));
    assert_null(lsm_planner_block(&g_pl, h0 + 1u));
    assert_non_null(lsm_planner_block(&g_pl, h0 + 2u));
    lsm_planner_apply_requests(&g_pl);
    assert_int_equal(g_pl.head, h0 + 2u);
    lsm_planner_post_release(&g_pl, h0 + 1u); /* earlier: nothing more */
    lsm_planner_apply_requests(&g_pl);
    assert_int_equal(g_pl.head, h0 + 2u);
    assert_int_equal(lsm_planner_count(&g_pl), n - 2u);
    lsm_planner_post_release(&g_pl, g_pl.tail + 5u); /* beyond the tail: stops there */
    assert_int_equal(lsm_planner_count(&g_pl), 0u);
    lsm_planner_update(&g_pl); /* a background call applies */
    assert_int_equal(g_pl.head, g_pl.tail);
}

static void test_horizon(void **state)
{
    (void)state;
    (void)setup_lines(4);
    const uint32_t h = g_pl.head;
    lsm_planner_post_horizon(&g_pl, h + 1u, (lsm_real)0.25, 30, h + 3u, 12);
    assert_int_equal(g_pl.horizon_blk, 0u); /* not yet applied */
    lsm_planner_apply_requests(&g_pl);
    assert_int_equal(g_pl.horizon_blk, h + 1u);
    assert_true(g_pl.horizon_off == (lsm_real)0.25 && g_pl.horizon_v == 30);
    assert_int_equal(g_pl.horizon_end, h + 3u);
    assert_true(g_pl.horizon_end_v == 12);
    assert_int_equal(g_pl.commit_dirty, 1);
    /* the same end again: not dirty */
    g_pl.commit_dirty = 0;
    lsm_planner_post_horizon(&g_pl, h + 2u, (lsm_real)0.5, -1, h + 3u, 12);
    lsm_planner_apply_requests(&g_pl);
    assert_int_equal(g_pl.commit_dirty, 0);
    assert_true(g_pl.horizon_v == 0); /* clamped, as lsm_planner_set_horizon does */
    /* the end moves and comes back between two applies: dirty, as two calls of lsm_planner_set_horizon make it */
    lsm_planner_post_horizon(&g_pl, h + 2u, (lsm_real)0.5, 20, h + 4u, 12);
    lsm_planner_post_horizon(&g_pl, h + 2u, (lsm_real)0.5, 20, h + 3u, 12);
    lsm_planner_apply_requests(&g_pl);
    assert_int_equal(g_pl.commit_dirty, 1);
    assert_int_equal(g_pl.horizon_end, h + 3u);
    /* a cursor: the point and speed move, the end stays; not dirty */
    g_pl.commit_dirty = 0;
    lsm_planner_post_cursor(&g_pl, h + 3u, (lsm_real)0.75, 25);
    assert_int_equal(g_pl.horizon_blk, h + 2u); /* not yet applied */
    lsm_planner_apply_requests(&g_pl);
    assert_int_equal(g_pl.horizon_blk, h + 3u);
    assert_true(g_pl.horizon_off == (lsm_real)0.75 && g_pl.horizon_v == 25);
    assert_int_equal(g_pl.horizon_end, h + 3u);
    assert_true(g_pl.horizon_end_v == 12);
    assert_int_equal(g_pl.commit_dirty, 0);
    lsm_planner_post_cursor(&g_pl, h + 3u, (lsm_real)0.875, -2);
    lsm_planner_apply_requests(&g_pl);
    assert_true(g_pl.horizon_off == (lsm_real)0.875 && g_pl.horizon_v == 0); /* clamped */
    assert_int_equal(g_pl.commit_dirty, 0);
}

static void test_stale_ack(void **state)
{
    (void)state;
    (void)setup_lines(2);
    assert_false(lsm_planner_piece_stale(&g_pl));
    const uint32_t seen = lsm_planner_stale_count(&g_pl); /* a piece is planned now */
    lsm_atomic_put_release(&g_pl.stale_set, seen + 1u);   /* the background invalidates the current piece */
    assert_true(lsm_planner_piece_stale(&g_pl));
    lsm_atomic_put_release(&g_pl.stale_set, seen + 2u); /* ... and the piece planned before it */
    lsm_planner_post_stale_ack(&g_pl, seen + 1u);       /* the tick takes that piece */
    assert_true(lsm_planner_piece_stale(&g_pl));        /* still stale: it was planned before the change */
    lsm_planner_post_stale_ack(&g_pl, seen + 2u);
    assert_false(lsm_planner_piece_stale(&g_pl));
}

#ifdef LSM_TEST_THREADS
#include <pthread.h>

#define POSTS 200000u
static lsm_atomic_u32 g_done;

/* Post i: every field is a function of i, so a torn copy is visible. Every CURSOR_RUN-th post is whole, the
 * others are cursors (as the interpolator's cruise posts them): their end is the last whole post's, end_of(i). */
#define CURSOR_RUN 8u
static uint32_t end_of(uint32_t i)
{
    return i - (i - 1u) % CURSOR_RUN;
}

static void *tick_thread(void *arg)
{
    (void)arg;
    const uint32_t h = g_pl.head, t = g_pl.tail; /* read before the background thread exists */
    for (uint32_t i = 1; i <= POSTS; i++) {
        if (end_of(i) == i)
            lsm_planner_post_horizon(&g_pl, h + i, (lsm_real)(i % 64u) / 8, (lsm_real)(i % 1000u), h + i + 3u,
                                     (lsm_real)(i % 512u) / 4);
        else
            lsm_planner_post_cursor(&g_pl, h + i, (lsm_real)(i % 64u) / 8, (lsm_real)(i % 1000u));
        if (i % 4096u == 0u && h + i / 4096u <= t)
            lsm_planner_post_release(&g_pl, h + i / 4096u);
    }
    lsm_atomic_put_release(&g_done, 1u);
    return NULL;
}

static void check_applied(uint32_t h, uint32_t *last_blk)
{
    const uint32_t i = g_pl.horizon_blk - h;
    if (i == 0u)
        return; /* nothing posted yet */
    assert_true(i >= *last_blk);
    assert_true(g_pl.horizon_off == (lsm_real)(i % 64u) / 8);
    assert_true(g_pl.horizon_v == (lsm_real)(i % 1000u));
    const uint32_t e = end_of(i);
    assert_int_equal(g_pl.horizon_end, h + e + 3u);
    assert_true(g_pl.horizon_end_v == (lsm_real)(e % 512u) / 4);
    *last_blk = i;
}

static void test_threads(void **state)
{
    (void)state;
    (void)setup_lines(8);
    const uint32_t h = g_pl.head, t = g_pl.tail;
    lsm_atomic_put(&g_done, 0u);
    pthread_t th;
    assert_int_equal(pthread_create(&th, NULL, tick_thread, NULL), 0);
    uint32_t last = 0, applies = 0, count_prev = lsm_planner_count(&g_pl);
    while (!lsm_atomic_get_acquire(&g_done)) {
        lsm_planner_apply_requests(&g_pl);
        check_applied(h, &last);
        const uint32_t c = lsm_planner_count(&g_pl);
        assert_true(c <= count_prev); /* the head only moves forward */
        count_prev = c;
        assert_true(!(g_pl.tail - g_pl.head > t - h));
        applies++;
    }
    assert_int_equal(pthread_join(th, NULL), 0);
    lsm_planner_apply_requests(&g_pl);
    check_applied(h, &last);
    assert_int_equal(last, POSTS);
    const uint32_t rel = h + POSTS / 4096u;
    assert_int_equal(g_pl.head, rel <= t ? rel : t);
    printf("planner requests: %u posts, %u applies by the other thread\n", POSTS, applies);
}
#endif

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_release),
        cmocka_unit_test(test_horizon),
        cmocka_unit_test(test_stale_ack),
#ifdef LSM_TEST_THREADS
        cmocka_unit_test(test_threads),
#endif
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
