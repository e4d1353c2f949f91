/*
 * test_co_emcy.c: the EMCY producer on its own: frame layout, error register latching per condition,
 * no repeat for an active condition, the error-reset frame when the last one clears, one-shot events,
 * the 0x1003 history (newest first, bounded, cleared by writing 0), frames suppressed when not allowed,
 * more conditions than the table tracks.
 */
#include "co_test_util.h"

static lsm_co_emcy em;
static lsm_can_frame store[32];
static lsm_can_txq q;

static int setup(void **state)
{
    (void)state;
    assert_int_equal(lsm_co_emcy_init(&em, 9), LSM_OK);
    assert_int_equal(lsm_can_txq_init(&q, store, 32), LSM_OK);
    return 0;
}

static size_t pop_all(lsm_can_frame *out, size_t cap)
{
    size_t n = 0;
    lsm_can_frame f;
    while (lsm_can_txq_pop(&q, &f)) {
        if (n < cap)
            out[n] = f;
        n++;
    }
    return n;
}

static void test_layout_and_latching(void **state)
{
    (void)state;
    lsm_can_frame f[8];
    assert_int_equal(lsm_co_emcy_raise(&em, 0x8611, LSM_CO_ERREG_PROFILE, 2, 0xA1B2C3D4u, true, &q), LSM_OK);
    assert_int_equal(pop_all(f, 8), 1);
    assert_int_equal(f[0].id, 0x89);
    assert_int_equal(f[0].dlc, 8);
    assert_int_equal(lsm_can_get_u16(&f[0].data[0]), 0x8611);
    assert_int_equal(f[0].data[2], LSM_CO_ERREG_PROFILE | LSM_CO_ERREG_GENERIC);
    assert_int_equal(f[0].data[3], 2);
    assert_int_equal(lsm_can_get_u32(&f[0].data[4]), 0xA1B2C3D4u);
    assert_int_equal(em.error_register, 0x21);
    /* again: already active, no frame */
    assert_int_equal(lsm_co_emcy_raise(&em, 0x8611, LSM_CO_ERREG_PROFILE, 2, 0, true, &q), LSM_OK);
    assert_int_equal(pop_all(f, 8), 0);
    /* the same code on another axis is another condition */
    assert_int_equal(lsm_co_emcy_raise(&em, 0x8611, LSM_CO_ERREG_PROFILE, 3, 0, true, &q), LSM_OK);
    assert_int_equal(lsm_co_emcy_raise(&em, 0x8130, LSM_CO_ERREG_COMM, 0x7F, 0, true, &q), LSM_OK);
    assert_int_equal(pop_all(f, 8), 2);
    assert_int_equal(em.error_register, 0x31);
    assert_true(lsm_co_emcy_is_active(&em, 0x8611, 3));
    /* clearing: register follows; the error reset only after the last one */
    assert_int_equal(lsm_co_emcy_clear(&em, 0x8130, 0x7F, true, &q), LSM_OK);
    assert_int_equal(pop_all(f, 8), 0);
    assert_int_equal(em.error_register, 0x21);
    assert_int_equal(lsm_co_emcy_clear(&em, 0x8611, 2, true, &q), LSM_OK);
    assert_int_equal(lsm_co_emcy_clear(&em, 0x8611, 2, true, &q), LSM_OK); /* not active: nothing */
    assert_int_equal(pop_all(f, 8), 0);
    assert_int_equal(lsm_co_emcy_clear(&em, 0x8611, 3, true, &q), LSM_OK);
    assert_int_equal(pop_all(f, 8), 1);
    assert_int_equal(lsm_can_get_u16(&f[0].data[0]), 0x0000);
    assert_int_equal(f[0].data[2], 0);
    assert_int_equal(em.error_register, 0);
}

static void test_events_and_history(void **state)
{
    (void)state;
    lsm_can_frame f[16];
    assert_int_equal(lsm_co_emcy_event(&em, 0x8210, LSM_CO_ERREG_COMM, 1, 0, true, &q), LSM_OK);
    assert_int_equal(pop_all(f, 16), 1);
    assert_int_equal(f[0].data[2], LSM_CO_ERREG_COMM | LSM_CO_ERREG_GENERIC);
    assert_int_equal(em.error_register, 0); /* not latched */
    for (uint16_t c = 1; c <= 10; c++)
        assert_int_equal(lsm_co_emcy_event(&em, (uint16_t)(0xFF00 + c), 0, (uint8_t)c, 0, true, &q), LSM_OK);
    assert_int_equal(pop_all(f, 16), 10);
    assert_int_equal(em.n_history, LSM_CO_EMCY_HISTORY);
    assert_int_equal(em.history[0], (10u << 16) | 0xFF0A); /* newest first */
    assert_int_equal(em.history[LSM_CO_EMCY_HISTORY - 1], (3u << 16) | 0xFF03);
    assert_int_equal(lsm_co_emcy_write_history_count(&em, 2), LSM_CO_ABORT_VALUE);
    assert_int_equal(lsm_co_emcy_write_history_count(&em, 0), 0);
    assert_int_equal(em.n_history, 0);
    assert_int_equal(em.history[0], 0);
}

static void test_suppressed_and_overflow(void **state)
{
    (void)state;
    lsm_can_frame f[32];
    assert_int_equal(lsm_co_emcy_raise(&em, 0x9000, LSM_CO_ERREG_GENERIC, 0xFF, 0, false, &q), LSM_OK);
    assert_int_equal(pop_all(f, 32), 0);       /* not allowed to send now */
    assert_int_equal(em.error_register, 0x01); /* but latched */
    assert_int_equal(em.n_history, 1);         /* and recorded */
    assert_int_equal(em.suppressed, 1);
    for (uint16_t c = 0; c < LSM_CO_EMCY_ACTIVE + 3; c++)
        assert_int_equal(lsm_co_emcy_raise(&em, (uint16_t)(0x5000 + c), LSM_CO_ERREG_VOLTAGE, 0, 0, true, &q), LSM_OK);
    assert_int_equal(pop_all(f, 32), LSM_CO_EMCY_ACTIVE + 3); /* every one is reported */
    assert_int_equal(em.n_active, LSM_CO_EMCY_ACTIVE);
    assert_int_equal(em.overflow, 4);
    /* the register stays latched until every tracked condition is gone */
    for (uint16_t c = 0; c < LSM_CO_EMCY_ACTIVE - 1; c++)
        assert_int_equal(lsm_co_emcy_clear(&em, (uint16_t)(0x5000 + c), 0, true, &q), LSM_OK);
    assert_true(em.error_register & LSM_CO_ERREG_VOLTAGE);
    assert_int_equal(lsm_co_emcy_clear(&em, 0x9000, 0xFF, true, &q), LSM_OK);
    assert_int_equal(em.error_register, 0);
    assert_int_equal(pop_all(f, 32), 1); /* error reset */
    assert_int_equal(lsm_co_emcy_init(NULL, 1), LSM_E_NULL);
    assert_int_equal(lsm_co_emcy_init(&em, 0), LSM_E_CO_NODE_ID);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_layout_and_latching, setup),
        cmocka_unit_test_setup(test_events_and_history, setup),
        cmocka_unit_test_setup(test_suppressed_and_overflow, setup),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
