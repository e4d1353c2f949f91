/*
 * json.c: strict JSON reader into a caller-owned token array (see json.h).
 */
#include "json.h"

#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct {
    const char *s;
    size_t n;
    size_t i;
    sim_json_tok *toks;
    int max;
    int count;
    int depth;
    sim_json_error *err;
} parser;

void sim_json_line_col(const char *text, size_t len, size_t offset, int *line, int *column)
{
    int l = 1, c = 1;
    for (size_t i = 0; i < offset && i < len; i++) {
        if (text[i] == '\n') {
            l++;
            c = 1;
        } else {
            c++;
        }
    }
    if (line)
        *line = l;
    if (column)
        *column = c;
}

static int fail(parser *p, size_t at, const char *fmt, ...)
{
    if (p->err) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(p->err->msg, sizeof p->err->msg, fmt, ap);
        va_end(ap);
        p->err->offset = at;
        sim_json_line_col(p->s, p->n, at, &p->err->line, &p->err->column);
    }
    return -1;
}

static void skip_ws(parser *p)
{
    while (p->i < p->n) {
        char c = p->s[p->i];
        if (c != ' ' && c != '\t' && c != '\n' && c != '\r')
            break;
        p->i++;
    }
}

static int new_tok(parser *p, sim_json_type type, size_t start, int parent)
{
    if (p->count >= p->max)
        return fail(p, start, "too many values (more than %d tokens)", p->max);
    int k = p->count++;
    p->toks[k] = (sim_json_tok){.type = type, .start = start, .end = start, .size = 0, .next = k + 1, .parent = parent};
    return k;
}

static int hexval(char c)
{
    if (c >= '0' && c <= '9')
        return c - '0';
    if (c >= 'a' && c <= 'f')
        return c - 'a' + 10;
    if (c >= 'A' && c <= 'F')
        return c - 'A' + 10;
    return -1;
}

static int read_hex4(const char *s, size_t n, size_t i, unsigned *out)
{
    if (i + 4 > n)
        return -1;
    unsigned v = 0;
    for (int k = 0; k < 4; k++) {
        int h = hexval(s[i + (size_t)k]);
        if (h < 0)
            return -1;
        v = v * 16u + (unsigned)h;
    }
    *out = v;
    return 0;
}

/* Length of a valid UTF-8 sequence at s[i] (1..4), or 0 if invalid. */
static size_t utf8_len(const unsigned char *s, size_t n, size_t i)
{
    unsigned char c = s[i];
    if (c < 0x80)
        return 1;
    size_t len;
    uint32_t cp;
    if (c >= 0xC2 && c <= 0xDF) {
        len = 2;
        cp = c & 0x1Fu;
    } else if (c >= 0xE0 && c <= 0xEF) {
        len = 3;
        cp = c & 0x0Fu;
    } else if (c >= 0xF0 && c <= 0xF4) {
        len = 4;
        cp = c & 0x07u;
    } else {
        return 0;
    }
    if (i + len > n)
        return 0;
    for (size_t k = 1; k < len; k++) {
        if ((s[i + k] & 0xC0u) != 0x80u)
            return 0;
        cp = (cp << 6) | (s[i + k] & 0x3Fu);
    }
    if ((len == 3 && cp < 0x800) || (len == 4 && (cp < 0x10000 || cp > 0x10FFFF)) || (cp >= 0xD800 && cp <= 0xDFFF))
        return 0; /* overlong, out of range, or an encoded surrogate */
    return len;
}

static int parse_string(parser *p, int parent)
{
    const size_t open = p->i;
    int k = new_tok(p, SIM_JSON_STRING, open + 1, parent);
    if (k < 0)
        return -1;
    p->i++;
    while (p->i < p->n) {
        unsigned char c = (unsigned char)p->s[p->i];
        if (c == '"') {
            p->toks[k].end = p->i;
            p->i++;
            return k;
        }
        if (c < 0x20)
            return fail(p, p->i, "control character 0x%02X in a string (escape it)", c);
        if (c == '\\') {
            if (p->i + 1 >= p->n)
                break;
            char e = p->s[p->i + 1];
            if (e == 'u') {
                unsigned u;
                if (read_hex4(p->s, p->n, p->i + 2, &u) != 0)
                    return fail(p, p->i, "bad \\u escape (needs 4 hex digits)");
                if (u >= 0xDC00 && u <= 0xDFFF)
                    return fail(p, p->i, "unpaired low surrogate \\u%04X", u);
                if (u >= 0xD800 && u <= 0xDBFF) {
                    unsigned lo;
                    if (p->i + 7 >= p->n || p->s[p->i + 6] != '\\' || p->s[p->i + 7] != 'u' ||
                        read_hex4(p->s, p->n, p->i + 8, &lo) != 0 || lo < 0xDC00 || lo > 0xDFFF)
                        return fail(p, p->i, "unpaired high surrogate \\u%04X", u);
                    p->i += 12;
                } else {
                    p->i += 6;
                }
                continue;
            }
            if (!strchr("\"\\/bfnrt", e) || e == '\0')
                return fail(p, p->i, "invalid escape \\%c", e);
            p->i += 2;
            continue;
        }
        size_t l = utf8_len((const unsigned char *)p->s, p->n, p->i);
        if (l == 0)
            return fail(p, p->i, "invalid UTF-8 in a string");
        p->i += l;
    }
    return fail(p, open, "unterminated string");
}

static int parse_number(parser *p, int parent)
{
    const size_t start = p->i;
    size_t i = p->i;
    const char *s = p->s;
    if (i < p->n && s[i] == '-')
        i++;
    if (i >= p->n || !(s[i] >= '0' && s[i] <= '9'))
        return fail(p, start, "invalid number");
    if (s[i] == '0') {
        i++;
        if (i < p->n && s[i] >= '0' && s[i] <= '9')
            return fail(p, start, "leading zeros are not allowed in numbers");
    } else {
        while (i < p->n && s[i] >= '0' && s[i] <= '9')
            i++;
    }
    if (i < p->n && s[i] == '.') {
        i++;
        if (i >= p->n || !(s[i] >= '0' && s[i] <= '9'))
            return fail(p, start, "invalid number: digits must follow the decimal point");
        while (i < p->n && s[i] >= '0' && s[i] <= '9')
            i++;
    }
    if (i < p->n && (s[i] == 'e' || s[i] == 'E')) {
        i++;
        if (i < p->n && (s[i] == '+' || s[i] == '-'))
            i++;
        if (i >= p->n || !(s[i] >= '0' && s[i] <= '9'))
            return fail(p, start, "invalid number: bad exponent");
        while (i < p->n && s[i] >= '0' && s[i] <= '9')
            i++;
    }
    char buf[64];
    size_t len = i - start;
    if (len >= sizeof buf)
        return fail(p, start, "number too long (%zu characters)", len);
    memcpy(buf, s + start, len);
    buf[len] = '\0';
    double v = strtod(buf, NULL);
    if (!isfinite(v))
        return fail(p, start, "number out of the range of a double");
    int k = new_tok(p, SIM_JSON_NUMBER, start, parent);
    if (k < 0)
        return -1;
    p->toks[k].end = i;
    p->i = i;
    return k;
}

static int parse_value(parser *p, int parent);

static bool same_key(const parser *p, int a, int b)
{
    char ba[256], bb[256];
    int la = sim_json_string(p->s, &p->toks[a], ba, sizeof ba);
    int lb = sim_json_string(p->s, &p->toks[b], bb, sizeof bb);
    if (la < 0 || lb < 0) /* very long keys: compare raw */
        return p->toks[a].end - p->toks[a].start == p->toks[b].end - p->toks[b].start &&
               memcmp(p->s + p->toks[a].start, p->s + p->toks[b].start, p->toks[a].end - p->toks[a].start) == 0;
    return la == lb && memcmp(ba, bb, (size_t)la) == 0;
}

static int parse_container(parser *p, int parent, bool object)
{
    const size_t open = p->i;
    if (p->depth >= SIM_JSON_MAX_DEPTH)
        return fail(p, open, "nesting deeper than %d", SIM_JSON_MAX_DEPTH);
    int k = new_tok(p, object ? SIM_JSON_OBJECT : SIM_JSON_ARRAY, open, parent);
    if (k < 0)
        return -1;
    p->depth++;
    p->i++;
    skip_ws(p);
    const char close = object ? '}' : ']';
    if (p->i < p->n && p->s[p->i] == close) {
        p->i++;
    } else {
        for (;;) {
            skip_ws(p);
            if (object) {
                if (p->i >= p->n || p->s[p->i] != '"')
                    return fail(p, p->i,
                                p->i < p->n && p->s[p->i] == '}' ? "trailing comma in object"
                                                                 : "expected a string key");
                int key = parse_string(p, k);
                if (key < 0)
                    return -1;
                /* duplicate keys: compare with the earlier keys of this object */
                for (int m = k + 1, j = 0; j < p->toks[k].size; j++, m = p->toks[m + 1].next) {
                    if (same_key(p, m, key))
                        return fail(p, p->toks[key].start - 1, "duplicate key \"%.*s\"",
                                    (int)(p->toks[key].end - p->toks[key].start), p->s + p->toks[key].start);
                }
                skip_ws(p);
                if (p->i >= p->n || p->s[p->i] != ':')
                    return fail(p, p->i, "expected ':' after a key");
                p->i++;
                skip_ws(p);
            } else if (p->i < p->n && p->s[p->i] == ']') {
                return fail(p, p->i, "trailing comma in array");
            }
            if (parse_value(p, k) < 0)
                return -1;
            p->toks[k].size++;
            skip_ws(p);
            if (p->i >= p->n)
                return fail(p, open, "unterminated %s", object ? "object" : "array");
            if (p->s[p->i] == ',') {
                p->i++;
                continue;
            }
            if (p->s[p->i] == close) {
                p->i++;
                break;
            }
            return fail(p, p->i, "expected ',' or '%c'", close);
        }
    }
    p->depth--;
    p->toks[k].end = p->i;
    p->toks[k].next = p->count;
    return k;
}

static int parse_literal(parser *p, int parent, const char *word, sim_json_type type)
{
    size_t l = strlen(word);
    if (p->i + l > p->n || memcmp(p->s + p->i, word, l) != 0)
        return fail(p, p->i, "invalid literal (expected %s)", word);
    int k = new_tok(p, type, p->i, parent);
    if (k < 0)
        return -1;
    p->i += l;
    p->toks[k].end = p->i;
    return k;
}

static int parse_value(parser *p, int parent)
{
    skip_ws(p);
    if (p->i >= p->n)
        return fail(p, p->i, "unexpected end of input (expected a value)");
    char c = p->s[p->i];
    int k;
    switch (c) {
    case '{': k = parse_container(p, parent, true); break;
    case '[': k = parse_container(p, parent, false); break;
    case '"': k = parse_string(p, parent); break;
    case 't': k = parse_literal(p, parent, "true", SIM_JSON_TRUE); break;
    case 'f': k = parse_literal(p, parent, "false", SIM_JSON_FALSE); break;
    case 'n': k = parse_literal(p, parent, "null", SIM_JSON_NULL); break;
    default:
        if (c == '-' || (c >= '0' && c <= '9'))
            k = parse_number(p, parent);
        else if ((unsigned char)c == 0xEF)
            return fail(p, p->i, "byte-order mark or invalid byte (not allowed)");
        else if (c == '/')
            return fail(p, p->i, "comments are not allowed in JSON");
        else if (c == '\'')
            return fail(p, p->i, "strings need double quotes");
        else
            return fail(p, p->i, "unexpected character '%c' (expected a value)", c >= 0x20 && c < 0x7F ? c : '?');
    }
    if (k >= 0)
        p->toks[k].next = p->count;
    return k;
}

int sim_json_parse(const char *text, size_t len, sim_json_tok *toks, int max_toks, sim_json_error *err)
{
    parser p = {.s = text, .n = len, .i = 0, .toks = toks, .max = max_toks, .count = 0, .depth = 0, .err = err};
    if (err)
        memset(err, 0, sizeof *err);
    if (!text || !toks || max_toks < 1)
        return fail(&p, 0, "no input or no token storage");
    if (parse_value(&p, -1) < 0)
        return -1;
    skip_ws(&p);
    if (p.i != p.n)
        return fail(&p, p.i, "extra data after the JSON value");
    return p.count;
}

static void put_utf8(char *buf, size_t *o, unsigned cp)
{
    if (cp < 0x80) {
        buf[(*o)++] = (char)cp;
    } else if (cp < 0x800) {
        buf[(*o)++] = (char)(0xC0 | (cp >> 6));
        buf[(*o)++] = (char)(0x80 | (cp & 0x3F));
    } else if (cp < 0x10000) {
        buf[(*o)++] = (char)(0xE0 | (cp >> 12));
        buf[(*o)++] = (char)(0x80 | ((cp >> 6) & 0x3F));
        buf[(*o)++] = (char)(0x80 | (cp & 0x3F));
    } else {
        buf[(*o)++] = (char)(0xF0 | (cp >> 18));
        buf[(*o)++] = (char)(0x80 | ((cp >> 12) & 0x3F));
        buf[(*o)++] = (char)(0x80 | ((cp >> 6) & 0x3F));
        buf[(*o)++] = (char)(0x80 | (cp & 0x3F));
    }
}

int sim_json_string(const char *text, const sim_json_tok *t, char *buf, size_t bufsize)
{
    if (!text || !t || !buf || bufsize == 0 || t->type != SIM_JSON_STRING)
        return -1;
    size_t o = 0;
    for (size_t i = t->start; i < t->end;) {
        if (o + 5 > bufsize) /* room for the longest UTF-8 sequence and the NUL */
            return -1;
        char c = text[i];
        if (c != '\\') {
            buf[o++] = c;
            i++;
            continue;
        }
        char e = text[i + 1];
        i += 2;
        switch (e) {
        case 'b': buf[o++] = '\b'; break;
        case 'f': buf[o++] = '\f'; break;
        case 'n': buf[o++] = '\n'; break;
        case 'r': buf[o++] = '\r'; break;
        case 't': buf[o++] = '\t'; break;
        case 'u': {
            unsigned u = 0, lo = 0;
            read_hex4(text, t->end, i, &u);
            i += 4;
            if (u >= 0xD800 && u <= 0xDBFF) {
                read_hex4(text, t->end, i + 2, &lo);
                i += 6;
                u = 0x10000u + ((u - 0xD800u) << 10) + (lo - 0xDC00u);
            }
            put_utf8(buf, &o, u);
            break;
        }
        default: buf[o++] = e; break; /* " \ / */
        }
    }
    buf[o] = '\0';
    return (int)o;
}

bool sim_json_string_eq(const char *text, const sim_json_tok *t, const char *s)
{
    char buf[512];
    int l = sim_json_string(text, t, buf, sizeof buf);
    return l >= 0 && strcmp(buf, s) == 0;
}

int sim_json_number(const char *text, const sim_json_tok *t, double *out)
{
    if (!text || !t || !out || t->type != SIM_JSON_NUMBER)
        return -1;
    char buf[64];
    size_t len = t->end - t->start;
    if (len >= sizeof buf)
        return -1;
    memcpy(buf, text + t->start, len);
    buf[len] = '\0';
    *out = strtod(buf, NULL);
    return 0;
}

int sim_json_find(const char *text, const sim_json_tok *toks, int obj, const char *key)
{
    if (!text || !toks || obj < 0 || toks[obj].type != SIM_JSON_OBJECT)
        return -1;
    for (int k = obj + 1, i = 0; i < toks[obj].size; i++, k = toks[k + 1].next)
        if (sim_json_string_eq(text, &toks[k], key))
            return k + 1;
    return -1;
}

const char *sim_json_type_name(sim_json_type t)
{
    switch (t) {
    case SIM_JSON_OBJECT: return "object";
    case SIM_JSON_ARRAY: return "array";
    case SIM_JSON_STRING: return "string";
    case SIM_JSON_NUMBER: return "number";
    case SIM_JSON_TRUE: return "true";
    case SIM_JSON_FALSE: return "false";
    case SIM_JSON_NULL: return "null";
    }
    return "?";
}
