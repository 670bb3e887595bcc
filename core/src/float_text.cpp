/* The shortest round-trip digits of a float come from Dragonbox (Jeon 2020; Debian
 * libdragonbox-dev, header only); this file only lays them out (float_text.h). No C++ exception
 * can leave it: Dragonbox's to_decimal is noexcept and nothing here allocates. */
#include "float_text.h"

#include <cmath>
#include <cstdint>

#include <dragonbox/dragonbox.h>

namespace {

/* The decimal digits of d (d > 0) into out, most significant first; returns their count. */
size_t put_digits(std::uint64_t d, char *out)
{
    char rev[20];
    size_t n = 0;
    do {
        rev[n++] = static_cast<char>('0' + d % 10u);
        d /= 10u;
    } while (d != 0u);
    for (size_t i = 0; i < n; ++i) out[i] = rev[n - 1 - i];
    return n;
}

/* The layout of float_text.h for either width: the significand and exponent come from
 * Dragonbox's shortest round-trip decimal of v. */
template <typename Real>
size_t real_text(Real v, char *out)
{
    size_t len = 0;
    if (std::isnan(v)) {
        out[0] = 'n', out[1] = 'a', out[2] = 'n';
        return 3;
    }
    if (std::signbit(v)) out[len++] = '-';
    if (std::isinf(v)) {
        out[len] = 'i', out[len + 1] = 'n', out[len + 2] = 'f';
        return len + 3;
    }
    if (v == Real(0)) {
        out[len++] = '0';
        return len;
    }
    /* v = significand * 10^exponent, the significand as short as round-tripping allows */
    auto dec = jkj::dragonbox::to_decimal(v, jkj::dragonbox::policy::sign::ignore,
                                          jkj::dragonbox::policy::trailing_zero::remove);
    char digits[20];
    size_t n = put_digits(static_cast<std::uint64_t>(dec.significand), digits);
    int point = static_cast<int>(n) + dec.exponent; /* digits before the decimal point */
    int first = point - 1;                          /* the power of ten of the first digit */
    int plain_max = sizeof(Real) == sizeof(float) ? 8 : 16;
    if (first >= -5 && first <= plain_max) {
        if (point <= 0) {
            out[len++] = '0';
            out[len++] = '.';
            for (int i = point; i < 0; ++i) out[len++] = '0';
            for (size_t i = 0; i < n; ++i) out[len++] = digits[i];
        } else {
            size_t whole = static_cast<size_t>(point);
            for (size_t i = 0; i < whole; ++i) out[len++] = i < n ? digits[i] : '0';
            if (whole < n) {
                out[len++] = '.';
                for (size_t i = whole; i < n; ++i) out[len++] = digits[i];
            }
        }
        return len;
    }
    out[len++] = digits[0];
    if (n > 1) {
        out[len++] = '.';
        for (size_t i = 1; i < n; ++i) out[len++] = digits[i];
    }
    out[len++] = 'e';
    if (first < 0) {
        out[len++] = '-';
        first = -first;
    }
    return len + put_digits(static_cast<std::uint64_t>(first), out + len);
}

} // namespace

extern "C" size_t xyl__float_text(float v, char out[XYL__FLOAT_TEXT_MAX])
{
    return real_text(v, out);
}

extern "C" size_t xyl__double_text(double v, char out[XYL__DOUBLE_TEXT_MAX])
{
    return real_text(v, out);
}
