/*
 * json.h: a small strict JSON reader (RFC 8259) for machine files and other host-side inputs.
 *
 * The parser fills a caller-provided token array in document order (a value's tokens follow it;
 * an object's members are key, value, key, value, ...) and never allocates. Strict means:
 * exactly one top-level value; no comments, trailing commas, single quotes, NaN/Infinity, leading
 * zeros, '+' signs or byte-order mark; strings must be valid UTF-8 without control characters,
 * with only the standard escapes and paired surrogates in \u escapes; numbers must fit a double
 * (1e400 is an error); duplicate keys in one object are an error (compared after unescaping);
 * nesting is limited to SIM_JSON_MAX_DEPTH. Errors carry a message, the byte offset, line and column.
 *
 * Walking the tokens:
 *   object o:  for (int k = o + 1, i = 0; i < t[o].size; i++, k = t[k + 1].next) { key = k; value = k + 1; }
 *   array a:   for (int e = a + 1, i = 0; i < t[a].size; i++, e = t[e].next) { element = e; }
 */
#ifndef LSM_SIM_JSON_H
#define LSM_SIM_JSON_H

#include <stdbool.h>
#include <stddef.h>

#define SIM_JSON_MAX_DEPTH 64

typedef enum sim_json_type {
    SIM_JSON_OBJECT = 1,
    SIM_JSON_ARRAY,
    SIM_JSON_STRING,
    SIM_JSON_NUMBER,
    SIM_JSON_TRUE,
    SIM_JSON_FALSE,
    SIM_JSON_NULL
} sim_json_type;

typedef struct sim_json_tok {
    sim_json_type type;
    size_t start; /* first byte of the value (for strings: after the opening quote) */
    size_t end;   /* one past the last byte (for strings: the closing quote) */
    int size;     /* objects: number of members; arrays: number of elements; else 0 */
    int next;     /* index of the first token after this value and everything inside it */
    int parent;   /* index of the enclosing object/array (for a member value: the object), -1 at top */
} sim_json_tok;

typedef struct sim_json_error {
    size_t offset; /* byte offset of the error */
    int line;      /* 1-based */
    int column;    /* 1-based, in bytes */
    char msg[128];
} sim_json_error;

/* Parses text[0 .. len) into toks (capacity max_toks). Returns the number of tokens (>= 1) or -1
 * with *err filled (err may be NULL). */
int sim_json_parse(const char *text, size_t len, sim_json_tok *toks, int max_toks, sim_json_error *err);

/* 1-based line and column of a byte offset. */
void sim_json_line_col(const char *text, size_t len, size_t offset, int *line, int *column);

/* Decodes a string token into buf (NUL-terminated UTF-8). Returns the length, or -1 if the token is
 * not a string or buf is too small. */
int sim_json_string(const char *text, const sim_json_tok *t, char *buf, size_t bufsize);

/* true if string token t equals s (after unescaping). */
bool sim_json_string_eq(const char *text, const sim_json_tok *t, const char *s);

/* Number token to double (the parser already checked it is finite). -1 if t is not a number. */
int sim_json_number(const char *text, const sim_json_tok *t, double *out);

/* Index of the value of member `key` in object `obj`, or -1. */
int sim_json_find(const char *text, const sim_json_tok *toks, int obj, const char *key);

/* "object", "array", "string", "number", "true", "false", "null". */
const char *sim_json_type_name(sim_json_type t);

#endif /* LSM_SIM_JSON_H */
