/* A line and token reader for the library's strict text formats (.skel, OBJ leaf meshes). Not
 * installed.
 *
 * Text is read a line at a time: LF or CRLF ends a line, a final line without a break counts,
 * and a trailing LF opens no empty last line. Tokens are runs of bytes other than ' ' and '\t';
 * '#' starts a comment that runs to the line's end. Numbers are parsed here rather than with
 * strtod, whose radix character depends on the C locale. Errors name a 1-based line and column.
 *
 *     xyl__text_reader r;
 *     xyl__text_init(&r, text, size, diag);
 *     while (xyl__text_next_line(&r)) {
 *         xyl__token t;
 *         while (xyl__text_next_token(&r, &t))
 *             if (!xyl__token_is(&t, "v")) return xyl__text_fail(&r, XYL_ERR_PARSE, t.col, "...");
 *     }
 *
 * next_line and next_token are inline: a .skel reader calls them once per number. */
#ifndef XYL_TEXT_READER_H
#define XYL_TEXT_READER_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "xyl_internal.h"

typedef struct xyl__token {
    const char *s;
    size_t n;
    uint32_t col; /* 1-based */
} xyl__token;

typedef struct xyl__text_reader {
    const char *text;
    size_t size;
    size_t next;      /* offset of the next line */
    uint32_t line_no; /* 1-based number of the current line (saturates) */
    const char *line; /* the current line without its LF / CRLF */
    size_t len;
    size_t cur;       /* cursor in the current line */
    size_t last_end;  /* offset just past the last token of the current line */
    bool open_end;    /* the current line ends the text without a line break */
    int64_t index;    /* the record being read, for diag.index; -1 for none */
    xyl_diag *diag;
} xyl__text_reader;

static inline uint32_t xyl__to_u32(size_t v)
{
    return v > UINT32_MAX ? UINT32_MAX : (uint32_t)v;
}

static inline bool xyl__text_is_blank(char c)
{
    return c == ' ' || c == '\t';
}

void xyl__text_init(xyl__text_reader *r, const char *text, size_t size, xyl_diag *diag);

/* Moves to the next line; false at the end of the text. */
static inline bool xyl__text_next_line(xyl__text_reader *r)
{
    if (r->next >= r->size) return false;
    const char *start = r->text + r->next;
    size_t left = r->size - r->next;
    const char *lf = memchr(start, '\n', left);
    size_t len = lf ? (size_t)(lf - start) : left;
    r->next += lf ? len + 1 : len;
    r->open_end = lf == NULL;
    if (len > 0 && start[len - 1] == '\r') --len;
    r->line = start;
    r->len = len;
    r->cur = 0;
    r->last_end = 0;
    if (r->line_no < UINT32_MAX) ++r->line_no;
    return true;
}

/* The next token of the current line; false at its end or at a comment. */
static inline bool xyl__text_next_token(xyl__text_reader *r, xyl__token *t)
{
    while (r->cur < r->len && xyl__text_is_blank(r->line[r->cur])) ++r->cur;
    if (r->cur >= r->len || r->line[r->cur] == '#') {
        r->cur = r->len;
        return false;
    }
    size_t start = r->cur;
    while (r->cur < r->len && !xyl__text_is_blank(r->line[r->cur]) && r->line[r->cur] != '#')
        ++r->cur;
    t->s = r->line + start;
    t->n = r->cur - start;
    t->col = xyl__to_u32(start + 1);
    r->last_end = r->cur;
    return true;
}

static inline bool xyl__token_is(const xyl__token *t, const char *word)
{
    size_t n = strlen(word);
    return t->n == n && memcmp(t->s, word, n) == 0;
}

/* s[0..n) equals lower_word, ASCII letters compared without case: tolower() would depend on the
 * locale. */
bool xyl__text_ieq(const char *s, size_t n, const char *lower_word);

/* A token for a message in out, which holds max_chars + 4 bytes: non-printable bytes shown as
 * '?', a token longer than max_chars cut there and followed by "...". Returns out. */
const char *xyl__text_show(const xyl__token *t, size_t max_chars, char *out);

/* Fills r's diag with the current line, col (0: none), r->index and the message; returns code. */
xyl_result xyl__text_fail(const xyl__text_reader *r, xyl_result code, uint32_t col,
                          const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;

/* Decimal digits only, at least one; saturates at UINT64_MAX so an absurd count reads as "too
 * many". False (and *out untouched) for anything else. */
bool xyl__text_u64(const char *s, size_t n, uint64_t *out);
/* An optional '-' and decimal digits, saturating at the int64_t range. */
bool xyl__text_i64(const char *s, size_t n, int64_t *out);

typedef enum xyl__num_status { XYL__NUM_OK, XYL__NUM_BAD, XYL__NUM_NON_FINITE } xyl__num_status;

/* [+-] (digits [. digits*] | . digits) [(e|E) [+-] digits] to the nearest double within a few
 * ulps, sign of zero kept; a value beyond the double range gives +-infinity, which each format
 * turns into its own error or limit. "nan", "inf" and "infinity" (any case, signed) give
 * XYL__NUM_NON_FINITE, any other text XYL__NUM_BAD; *out is set only for XYL__NUM_OK. */
xyl__num_status xyl__text_real(const char *s, size_t n, double *out);

#endif
