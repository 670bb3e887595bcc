/* The line and token reader of the library's text formats (core/internal/text_reader.h). */
#include <math.h>
#include <stdio.h>

#include "text_reader.h"

/* Significant digits kept when parsing a number: exact in a uint64_t, and more than a double
 * needs, so dropping the rest cannot change the nearest float. */
#define MAX_SIGNIFICANT_DIGITS 19
/* |decimal exponent| beyond which every non-zero double is 0 or infinite. */
#define MAX_DECIMAL_EXPONENT 400
/* Written exponents saturate here: far beyond MAX_DECIMAL_EXPONENT, yet adding the digit count
 * of any text that fits in memory cannot overflow an int64_t. */
#define MAX_EXPONENT_DIGITS_VALUE (INT64_C(1) << 56)

void xyl__text_init(xyl__text_reader *r, const char *text, size_t size, xyl_diag *diag)
{
    memset(r, 0, sizeof *r);
    r->text = text;
    r->size = size;
    r->index = -1;
    r->diag = diag;
}

bool xyl__text_ieq(const char *s, size_t n, const char *lower_word)
{
    if (n != strlen(lower_word)) return false;
    for (size_t i = 0; i < n; ++i) {
        char c = s[i] >= 'A' && s[i] <= 'Z' ? (char)(s[i] - 'A' + 'a') : s[i];
        if (c != lower_word[i]) return false;
    }
    return true;
}

const char *xyl__text_show(const xyl__token *t, size_t max_chars, char *out)
{
    size_t n = t->n > max_chars ? max_chars : t->n;
    for (size_t i = 0; i < n; ++i) {
        unsigned char c = (unsigned char)t->s[i];
        out[i] = c >= 0x20 && c < 0x7f ? (char)c : '?';
    }
    strcpy(out + n, t->n > n ? "..." : "");
    return out;
}

xyl_result xyl__text_fail(const xyl__text_reader *r, xyl_result code, uint32_t col,
                          const char *fmt, ...)
{
    char msg[XYL_DIAG_MESSAGE_SIZE];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    return xyl__fail(r->diag, code, r->line_no, col, r->index, "%s", msg);
}

static bool is_digit(char c)
{
    return c >= '0' && c <= '9';
}

bool xyl__text_u64(const char *s, size_t n, uint64_t *out)
{
    if (n == 0) return false;
    uint64_t v = 0;
    for (size_t i = 0; i < n; ++i) {
        if (!is_digit(s[i])) return false;
        unsigned d = (unsigned)(s[i] - '0');
        v = v > (UINT64_MAX - d) / 10 ? UINT64_MAX : v * 10 + d;
    }
    *out = v;
    return true;
}

bool xyl__text_i64(const char *s, size_t n, int64_t *out)
{
    size_t skip = n > 0 && s[0] == '-' ? 1 : 0;
    bool neg = skip == 1;
    uint64_t v;
    if (!xyl__text_u64(s + skip, n - skip, &v)) return false;
    if (v > (uint64_t)INT64_MAX) *out = neg ? INT64_MIN : INT64_MAX;
    else *out = neg ? -(int64_t)v : (int64_t)v;
    return true;
}

typedef struct decimal {
    uint64_t mant; /* significant digits */
    int digits;    /* how many are in mant */
    int64_t exp10; /* value = mant * 10^exp10 */
    bool any;      /* a digit was seen */
} decimal;

static void add_digit(decimal *d, char c, bool fraction)
{
    unsigned v = (unsigned)(c - '0');
    d->any = true;
    if (d->mant == 0 && v == 0) {
        d->exp10 -= fraction; /* leading zeros are not significant */
    } else if (d->digits < MAX_SIGNIFICANT_DIGITS) {
        d->mant = d->mant * 10 + v;
        d->digits++;
        d->exp10 -= fraction;
    } else {
        d->exp10 += !fraction; /* a dropped integer digit still scales the value */
    }
}

/* Parses digits [. digits] [e [+-] digits] from s[*i]; false on a malformed exponent. */
static bool parse_decimal(const char *s, size_t n, size_t *i, decimal *d)
{
    for (; *i < n && is_digit(s[*i]); ++*i) add_digit(d, s[*i], false);
    if (*i < n && s[*i] == '.')
        for (++*i; *i < n && is_digit(s[*i]); ++*i) add_digit(d, s[*i], true);
    if (*i >= n || (s[*i] != 'e' && s[*i] != 'E')) return true;
    ++*i;
    bool neg = *i < n && s[*i] == '-';
    if (*i < n && (s[*i] == '-' || s[*i] == '+')) ++*i;
    if (*i >= n || !is_digit(s[*i])) return false;
    int64_t e = 0;
    for (; *i < n && is_digit(s[*i]); ++*i)
        if (e < MAX_EXPONENT_DIGITS_VALUE) e = e * 10 + (s[*i] - '0');
    d->exp10 += neg ? -e : e;
    return true;
}

xyl__num_status xyl__text_real(const char *s, size_t n, double *out)
{
    size_t i = n > 0 && (s[0] == '-' || s[0] == '+') ? 1 : 0;
    bool neg = i == 1 && s[0] == '-';
    /* Only a letter can start a word; a .skel reader parses millions of numbers. */
    bool letter = i < n && ((s[i] >= 'a' && s[i] <= 'z') || (s[i] >= 'A' && s[i] <= 'Z'));
    if (letter && (xyl__text_ieq(s + i, n - i, "nan") || xyl__text_ieq(s + i, n - i, "inf") ||
                   xyl__text_ieq(s + i, n - i, "infinity")))
        return XYL__NUM_NON_FINITE;
    decimal d = {0, 0, 0, false};
    if (!parse_decimal(s, n, &i, &d) || !d.any || i != n) return XYL__NUM_BAD;
    double v = 0.0;
    if (d.mant != 0 && d.exp10 > MAX_DECIMAL_EXPONENT) {
        v = HUGE_VAL;
    } else if (d.mant != 0 && d.exp10 >= -MAX_DECIMAL_EXPONENT) {
        /* 10^k is exact up to k = 22: dividing by it rounds once, multiplying by the inexact
         * 10^-k would round twice. */
        v = d.exp10 < 0 ? (double)d.mant / pow(10.0, (double)-d.exp10)
                        : (double)d.mant * pow(10.0, (double)d.exp10);
    }
    *out = neg ? -v : v;
    return XYL__NUM_OK;
}
