/*
 * test_sim_json.c: the strict JSON reader (host_sim/json.c).
 *
 * Valid documents parse into the expected token tree (types, sizes, next links, decoded strings and
 * numbers); each kind of non-strict input is rejected with a message and the right line/column.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include <cmocka.h>

#include "json.h"

static sim_json_tok g_toks[256];

static int parse(const char *s, sim_json_error *e)
{
    return sim_json_parse(s, strlen(s), g_toks, 256, e);
}

static void test_valid(void **state)
{
    (void)state;
    const char *s =
        "{\n  \"a\": [1, -2.5e3, 0, 0.125, true, false, null],\n  \"b\": {\"c\": \"x\\u00e9\\ud83d\\ude00\\n\\\"\"},"
        "\n  \"d\": [], \"e\": {}, \"\\u0061b\": \"caf\xC3\xA9\"\n}";
    sim_json_error e;
    int n = parse(s, &e);
    if (n < 0)
        print_error("%d:%d %s\n", e.line, e.column, e.msg);
    assert_int_equal(n, 20);
    assert_int_equal(g_toks[0].type, SIM_JSON_OBJECT);
    assert_int_equal(g_toks[0].size, 5);
    assert_int_equal(g_toks[0].next, 20);
    int a = sim_json_find(s, g_toks, 0, "a");
    assert_int_equal(a, 2);
    assert_int_equal(g_toks[a].type, SIM_JSON_ARRAY);
    assert_int_equal(g_toks[a].size, 7);
    double vals[3];
    int el = a + 1;
    for (int i = 0; i < 3; i++, el = g_toks[el].next)
        assert_int_equal(sim_json_number(s, &g_toks[el], &vals[i]), 0);
    assert_true(vals[0] == 1 && vals[1] == -2500 && vals[2] == 0);
    assert_int_equal(g_toks[a + 5].type, SIM_JSON_TRUE);
    assert_int_equal(g_toks[a + 6].type, SIM_JSON_FALSE);
    assert_int_equal(g_toks[a + 7].type, SIM_JSON_NULL);
    assert_int_equal(g_toks[a].next, a + 8);
    int b = sim_json_find(s, g_toks, 0, "b");
    int c = sim_json_find(s, g_toks, b, "c");
    char buf[64];
    assert_int_equal(sim_json_string(s, &g_toks[c], buf, sizeof buf), 9);
    assert_string_equal(buf, "x\xC3\xA9\xF0\x9F\x98\x80\n\"");
    assert_int_equal(sim_json_string(s, &g_toks[c], buf, 6), -1); /* too small */
    assert_true(sim_json_string_eq(s, &g_toks[sim_json_find(s, g_toks, 0, "ab")], "caf\xC3\xA9"));
    assert_int_equal(g_toks[sim_json_find(s, g_toks, 0, "d")].size, 0);
    assert_int_equal(sim_json_find(s, g_toks, 0, "zz"), -1);
    assert_int_equal(sim_json_find(s, g_toks, a, "a"), -1); /* not an object */
    assert_int_equal(g_toks[c].parent, b);
    assert_int_equal(parse("  42  ", &e), 1);
    assert_int_equal(parse("\"\"", &e), 1);
    assert_int_equal(parse("1E+2", &e), 1);
    assert_int_equal(parse("-0.0e-0", &e), 1);
    assert_string_equal(sim_json_type_name(SIM_JSON_NUMBER), "number");
}

static void bad(const char *s, const char *msg, int line, int col)
{
    sim_json_error e;
    int n = parse(s, &e);
    if (n >= 0 || !strstr(e.msg, msg) || e.line != line || e.column != col)
        print_error("input %s: n=%d, %d:%d %s\n", s, n, e.line, e.column, n < 0 ? e.msg : "");
    assert_int_equal(n, -1);
    assert_non_null(strstr(e.msg, msg));
    assert_int_equal(e.line, line);
    assert_int_equal(e.column, col);
}

static void test_strict(void **state)
{
    (void)state;
    bad("", "unexpected end", 1, 1);
    bad("{\"a\": 1,}", "trailing comma", 1, 9);
    bad("[1, 2,]", "trailing comma", 1, 7);
    bad("{\"a\": 1} x", "extra data", 1, 10);
    bad("{\"a\": 1}{}", "extra data", 1, 9);
    bad("// c\n{}", "comments", 1, 1);
    bad("{\"a\": 1 /* c */}", "expected ','", 1, 9);
    bad("{'a': 1}", "expected a string key", 1, 2);
    bad("['a']", "double quotes", 1, 2);
    bad("[01]", "leading zeros", 1, 2);
    bad("[+1]", "unexpected character '+'", 1, 2);
    bad("[1.]", "digits must follow", 1, 2);
    bad("[.5]", "unexpected character '.'", 1, 2);
    bad("[1e]", "bad exponent", 1, 2);
    bad("[NaN]", "unexpected character 'N'", 1, 2);
    bad("[-Infinity]", "invalid number", 1, 2);
    bad("[1e400]", "out of the range", 1, 2);
    bad("[tru]", "expected true", 1, 2);
    bad("[\"a\\x\"]", "invalid escape", 1, 4);
    bad("[\"\\u12G4\"]", "bad \\u escape", 1, 3);
    bad("[\"\\ud83d\"]", "unpaired high surrogate", 1, 3);
    bad("[\"\\ude00\"]", "unpaired low surrogate", 1, 3);
    bad("[\"a\tb\"]", "control character", 1, 4);
    bad("[\"\xC3\x28\"]", "invalid UTF-8", 1, 3);
    bad("[\"\xC0\xAF\"]", "invalid UTF-8", 1, 3);     /* overlong */
    bad("[\"\xED\xA0\x80\"]", "invalid UTF-8", 1, 3); /* encoded surrogate */
    bad("\xEF\xBB\xBF{}", "byte-order mark", 1, 1);
    bad("[\"abc", "unterminated string", 1, 2);
    bad("[1, 2", "unterminated array", 1, 1);
    bad("{\n\"a\": 1,\n\"b\": 2,\n\"a\": 3}", "duplicate key \"a\"", 4, 1);
    bad("{\"a\": 1, \"\\u0061\": 2}", "duplicate key", 1, 10);
    bad("{\"a\" 1}", "expected ':'", 1, 6);
    bad("[1 2]", "expected ','", 1, 4);
    char deep[200];
    memset(deep, '[', 100);
    memset(deep + 100, ']', 100);
    sim_json_error e;
    assert_int_equal(sim_json_parse(deep, 200, g_toks, 256, &e), -1);
    assert_non_null(strstr(e.msg, "nesting deeper than 64"));
    assert_int_equal(sim_json_parse("[1,2,3]", 7, g_toks, 3, &e), -1);
    assert_non_null(strstr(e.msg, "too many values"));
    assert_int_equal(sim_json_parse("[1,2,3]", 7, g_toks, 4, &e), 4);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_valid),
        cmocka_unit_test(test_strict),
    };
    return cmocka_run_group_tests_name("sim_json", tests, NULL, NULL);
}
